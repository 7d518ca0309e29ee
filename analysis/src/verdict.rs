//! The verdict of a run, computed from its rows: per scene × resolution (× effect) of an image
//! study, the fastest exact configuration (with the ones statistically tied with it) and its
//! floor, the fastest within each RMSE budget, and the exact rows left out because their GPU
//! time is not trusted. `report` writes it (the page's first table, the end of `mfx sweep`),
//! so the two cannot disagree with each other or with the CSV.

use schema::cols;

use crate::data::{platform, platforms, resolution, Rec, Runs};

/// RMSE budgets (vs the ground truth) the summary names the fastest configuration under.
pub const BUDGETS: [f64; 2] = [1e-3, 1e-2];

/// Studies whose rows carry an image error vs the ground truth (`rmse`).
pub const IMAGE_STUDIES: [&str; 2] = ["methods", "stability"];

/// A configuration named by the verdict, with the candidates whose time interval overlaps its
/// own ("tied with N": the data cannot tell them apart).
#[derive(Clone, Debug)]
pub struct Pick<'a> {
    pub row: &'a Rec,
    pub ties: Vec<&'a Rec>,
}

/// The verdict of one scene × resolution (× effect) of an image study.
#[derive(Clone, Debug)]
pub struct Verdict<'a> {
    pub study: String,
    pub scene: String,
    pub res: String,
    pub effect: String,
    /// The configurations ranked (ok, not floors).
    pub rows: Vec<&'a Rec>,
    pub fastest_exact: Option<Pick<'a>>,
    /// Exact rows left out of the ranking because their GPU time is not trusted.
    pub exact_untrusted: Vec<&'a Rec>,
    /// (RMSE budget, the fastest configuration whose RMSE is within it).
    pub budgets: Vec<(f64, Option<Pick<'a>>)>,
    pub floor_ms: Option<f64>,
    /// The row with the smallest RMSE (named when nothing was exact).
    pub best_error: Option<&'a Rec>,
}

/// Whether two rows' time intervals overlap (equal medians when either has none).
pub fn overlap(a: &Rec, b: &Rec) -> bool {
    match (a.gpu_ci(), b.gpu_ci()) {
        (Some((alo, ahi)), Some((blo, bhi))) => alo <= bhi && blo <= ahi,
        _ => a.trusted_ms() == b.trusted_ms(),
    }
}

/// The fastest of `rows` by trusted GPU time, with the others tied with it.
pub fn fastest<'a>(rows: &[&'a Rec]) -> Option<Pick<'a>> {
    let timed: Vec<&'a Rec> = rows
        .iter()
        .copied()
        .filter(|r| r.trusted_ms().is_some())
        .collect();
    let row = timed
        .iter()
        .copied()
        .min_by(|a, b| a.trusted_ms().unwrap().total_cmp(&b.trusted_ms().unwrap()))?;
    let ties = timed
        .into_iter()
        .filter(|r| !std::ptr::eq(*r, row) && overlap(r, row))
        .collect();
    Some(Pick { row, ties })
}

/// Studies whose verdict ranks configurations by image error.
fn image_verdict<'a>(
    study: &str,
    scene: &str,
    res: &str,
    effect: &str,
    rows: Vec<&'a Rec>,
    floors: &[&'a Rec],
) -> Verdict<'a> {
    let exact: Vec<&Rec> = rows
        .iter()
        .copied()
        .filter(|r| r.exact_result() == Some(true))
        .collect();
    // Exact but not rankable by time: timestamps that miss part of the frame, or none at all
    // (GLES in wgpu has no timer queries): such rows are named, not hidden behind "none exact".
    let exact_untrusted = exact
        .iter()
        .copied()
        .filter(|r| r.trusted_ms().is_none())
        .collect();
    let budgets = BUDGETS
        .iter()
        .map(|&b| {
            let within: Vec<&Rec> = rows
                .iter()
                .copied()
                .filter(|r| r.f(cols::RMSE).is_some_and(|e| e <= b))
                .collect();
            (b, fastest(&within))
        })
        .collect();
    let best_error = rows
        .iter()
        .copied()
        .filter(|r| r.f(cols::RMSE).is_some())
        .min_by(|a, b| {
            a.f(cols::RMSE)
                .unwrap()
                .total_cmp(&b.f(cols::RMSE).unwrap())
        });
    Verdict {
        study: study.to_string(),
        scene: scene.to_string(),
        res: res.to_string(),
        effect: effect.to_string(),
        fastest_exact: fastest(&exact),
        exact_untrusted,
        budgets,
        floor_ms: floors
            .iter()
            .find(|r| r.get(cols::METHOD) == "floor_depth")
            .and_then(|r| r.trusted_ms()),
        best_error,
        rows,
    }
}

/// Every verdict of the image studies, per platform, study, scene, resolution (and effect).
pub fn verdicts(runs: &Runs) -> Vec<(String, Verdict<'_>)> {
    let mut out = Vec::new();
    for p in platforms(runs) {
        let rows: Vec<&Rec> = runs.rows.iter().filter(|r| platform(r) == p).collect();
        for study in IMAGE_STUDIES {
            let ok: Vec<&Rec> = rows
                .iter()
                .copied()
                .filter(|r| r.get(cols::STUDY) == study && r.ok())
                .collect();
            let methods: Vec<&Rec> = ok.iter().copied().filter(|r| !r.is_floor()).collect();
            let effects = Runs::distinct(methods.iter().copied(), cols::EFFECT).len() > 1;
            for (key, g) in Runs::group_by(methods.iter().copied(), |r| {
                let e = if effects { r.get(cols::EFFECT) } else { "" };
                format!("{}\u{0}{}\u{0}{e}", r.get(cols::SCENE_LABEL), resolution(r))
            }) {
                if !g.iter().any(|r| r.f(cols::RMSE).is_some()) {
                    continue;
                }
                let mut parts = key.split('\u{0}');
                let (label, res, effect) = (
                    parts.next().unwrap_or(""),
                    parts.next().unwrap_or(""),
                    parts.next().unwrap_or(""),
                );
                let floors: Vec<&Rec> = ok
                    .iter()
                    .copied()
                    .filter(|r| {
                        r.is_floor() && r.get(cols::SCENE_LABEL) == label && resolution(r) == res
                    })
                    .collect();
                out.push((
                    p.clone(),
                    image_verdict(study, label, res, effect, g, &floors),
                ));
            }
        }
    }
    out
}
