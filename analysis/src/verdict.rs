//! The verdict of a run, computed from its rows: per scene × resolution (× effect) of an image
//! study, the fastest configuration exact by construction (with the ones statistically tied
//! with it) and its floor, apart from it the fastest that was exact in this run only (a method
//! that claims no exactness, such as a racy read-modify-write that lost nothing this time), the
//! fastest within each RMSE budget, and the rows left out of the ranking because their GPU time
//! is not trusted, with why. What kind of adapter measured the times (`software`) is part of it:
//! a CPU rasteriser's times say nothing of a GPU's. `report` writes it (the page's first table, the end of `mfx sweep`),
//! so the two cannot disagree with each other or with the CSV.

use schema::cols;
use schema::StudyKind;

use crate::data::{platform, platforms, resolution, Rec, Runs};

/// RMSE budgets (vs the ground truth) the summary names the fastest configuration under.
pub const BUDGETS: [f64; 2] = [1e-3, 1e-2];

/// Studies whose rows carry an image error vs the ground truth (`rmse`).
pub const IMAGE_STUDIES: [StudyKind; 2] = [StudyKind::Methods, StudyKind::Stability];

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
    /// The fastest configuration exact by construction: its method claims every fragment
    /// (`claims_exact`) and it was exact in this run.
    pub fastest_exact: Option<Pick<'a>>,
    /// The fastest configuration exact in this run, when it is one whose method claims no
    /// exactness (`claims_exact = false`: exact here because, e.g., no race happened) and it is
    /// faster than `fastest_exact` (or there is none). Never called "fastest exact".
    pub exact_in_run: Option<Pick<'a>>,
    /// Exact rows left out of the ranking because their GPU time is not trusted.
    pub exact_untrusted: Vec<&'a Rec>,
    /// Every row left out of the ranking by time (no trusted GPU time), exact or not.
    pub untrusted: Vec<&'a Rec>,
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

/// Whether a row is exact by construction: exact in this run and its method claims every
/// fragment. A CSV without `claims_exact` (schema ≤ 2) judged `exact` from the claim already.
pub fn exact_by_construction(r: &Rec) -> bool {
    r.exact_result() == Some(true) && r.claims_exact() != Some(false)
}

/// Why a row has no trusted GPU time, in words.
pub fn untrusted_reason(r: &Rec) -> &'static str {
    if r.f(cols::GPU_MS_MEDIAN).is_none() {
        "no GPU time: the adapter gave no timestamps"
    } else {
        "its GPU timestamps miss part of the frame (gpu_time_trusted = false)"
    }
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
    let untrusted = rows
        .iter()
        .copied()
        .filter(|r| r.trusted_ms().is_none())
        .collect();
    let by_construction: Vec<&Rec> = exact
        .iter()
        .copied()
        .filter(|r| exact_by_construction(r))
        .collect();
    let fastest_exact = fastest(&by_construction);
    let exact_in_run = fastest(&exact).filter(|p| !exact_by_construction(p.row));
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
        fastest_exact,
        exact_in_run,
        exact_untrusted,
        untrusted,
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
                .filter(|r| r.get(cols::STUDY) == study.name() && r.ok())
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
                    image_verdict(study.name(), label, res, effect, g, &floors),
                ));
            }
        }
    }
    out
}

/// A method left out of the ranking by time in some verdicts (its GPU time not trusted).
#[derive(Clone, Debug, PartialEq)]
pub struct LeftOut {
    pub platform: String,
    pub method: String,
    /// Verdicts (scene × resolution × effect) it was left out of, of `of` on its platform.
    pub verdicts: usize,
    pub of: usize,
    pub reason: &'static str,
}

/// Per platform and method, the verdicts a method was left out of because its GPU time is not
/// trusted, with the reason: said on the first screen, never left to a table cell.
pub fn left_out(vs: &[(String, Verdict<'_>)]) -> Vec<LeftOut> {
    let mut out: Vec<LeftOut> = Vec::new();
    for p in Runs::distinct_strings(vs.iter().map(|(p, _)| p.as_str())) {
        let mine: Vec<&Verdict> = vs.iter().filter(|(q, _)| *q == p).map(|(_, v)| v).collect();
        for v in &mine {
            for r in &v.untrusted {
                let m = r.get(cols::METHOD);
                let reason = untrusted_reason(r);
                match out
                    .iter_mut()
                    .find(|l| l.platform == p && l.method == m && l.reason == reason)
                {
                    Some(l) => l.verdicts += 1,
                    None => out.push(LeftOut {
                        platform: p.clone(),
                        method: m.to_string(),
                        verdicts: 1,
                        of: mine.len(),
                        reason,
                    }),
                }
            }
        }
    }
    // A method with several untrusted rows in one verdict counts that verdict once.
    for l in &mut out {
        l.verdicts = vs
            .iter()
            .filter(|(q, v)| {
                *q == l.platform
                    && v.untrusted
                        .iter()
                        .any(|r| r.get(cols::METHOD) == l.method && untrusted_reason(r) == l.reason)
            })
            .count();
    }
    out
}

/// What measured a platform's times when it is a software adapter (a CPU rasteriser such as
/// lavapipe or llvmpipe): its resolutions and sample counts, and whether the suite's
/// `[software]` profile was applied (run.json beside the CSV; `None` where none says).
#[derive(Clone, Debug, PartialEq)]
pub struct Software {
    pub platform: String,
    pub adapter: String,
    pub resolutions: Vec<String>,
    /// Distinct kept sample counts of its timed rows, smallest first.
    pub samples: Vec<usize>,
    pub profile: Option<bool>,
}

/// The software adapters among a run's platforms (`device_type = cpu`).
pub fn software(runs: &Runs) -> Vec<Software> {
    let profile = runs.sources.iter().find_map(|csv| {
        let text = std::fs::read_to_string(csv.with_file_name("run.json")).ok()?;
        let v: serde_json::Value = serde_json::from_str(&text).ok()?;
        v.get("software_profile")?.as_bool()
    });
    let mut out = Vec::new();
    for p in platforms(runs) {
        let rows: Vec<&Rec> = runs
            .rows
            .iter()
            .filter(|r| platform(r) == p && r.get(cols::DEVICE_TYPE) == "cpu")
            .collect();
        let Some(first) = rows.first() else { continue };
        let ok: Vec<&Rec> = rows.iter().copied().filter(|r| r.ok()).collect();
        let mut samples: Vec<usize> = ok
            .iter()
            .filter(|r| r.f(cols::GPU_MS_MEDIAN).is_some())
            .filter_map(|r| r.samples())
            .collect();
        samples.sort_unstable();
        samples.dedup();
        out.push(Software {
            adapter: first.get(cols::ADAPTER).to_string(),
            resolutions: Runs::distinct_by(&ok, resolution),
            samples,
            profile,
            platform: p,
        });
    }
    out
}
