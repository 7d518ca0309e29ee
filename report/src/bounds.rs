//! "What bounds each method": for every trusted, timed point with per-pass times, the pass that
//! takes the most GPU time, its share of the frame, how it compares with the depth-only floor of
//! the same scene and resolution (a pass near the floor costs no more than rasterising the scene
//! once, whatever it does), and how far the frame's declared traffic is from the adapter's peak
//! memory bandwidth. Written as `bounds.md` beside the report (for RUN.md) and as a section of
//! the page.

use std::collections::BTreeMap;
use std::fmt::Write;

use schema::{cols, PointKey};

use crate::cells::short;
use mfx_analysis::data::{resolution, Rec, Runs};

/// A limiting pass within this factor of the depth-only floor costs about what rasterising the
/// scene once costs, which no raster capture avoids. It says nothing of what bounds the pass
/// itself (a compute resolve rasterises nothing): the words say only the comparison.
pub const AT_FLOOR: f64 = 1.25;

/// The method whose time is the depth-only floor.
const FLOOR_DEPTH: &str = "floor_depth";

/// One point's bound.
#[derive(Clone, Debug, PartialEq)]
pub struct Bound {
    pub study: String,
    pub scene: String,
    pub resolution: String,
    /// Method and the axes the suite set.
    pub config: String,
    pub gpu_ms: f64,
    /// The slowest pass: its label and median ms.
    pub pass: String,
    pub pass_ms: f64,
    /// pass_ms / the sum of all passes' ms.
    pub share: f64,
    /// The depth-only floor of the same study, scene and resolution, when the run has one.
    pub floor_ms: Option<f64>,
    pub fragments_per_s: Option<f64>,
    pub bytes_per_s: Option<f64>,
    /// bytes_per_s / the roof the row is read against (`peak_bandwidth_frac`).
    pub peak_frac: Option<f64>,
    /// The measured roof it is read against: Some(true) the L2's, Some(false) the DRAM's; None
    /// for runs without measured roofs (NVML's spec bandwidth).
    pub l2_resident: Option<bool>,
}

impl Bound {
    /// In words: what the slowest pass is bound by, as far as the run can say.
    pub fn verdict(&self) -> String {
        let floor = match self.floor_ms {
            Some(f) if f > 0.0 && self.pass_ms <= AT_FLOOR * f => {
                format!(
                    "near the depth-only floor ({}× it)",
                    short(Some(self.pass_ms / f))
                )
            }
            Some(f) if f > 0.0 => {
                format!("{}× the depth-only floor", short(Some(self.pass_ms / f)))
            }
            _ => "no floor in this run".into(),
        };
        let roof = match self.l2_resident {
            Some(true) => "the measured L2 roof (its working set fits the L2)",
            Some(false) => "the measured memory roof",
            None => "peak bandwidth",
        };
        match self.peak_frac {
            Some(p) if p > 0.0 => format!(
                "{floor}; declared traffic at {} % of {roof} ({}× from the memory bound)",
                short(Some(100.0 * p)),
                short(Some(1.0 / p))
            ),
            _ => format!("{floor}; peak bandwidth unknown"),
        }
    }
}

/// The per-pass times of a row (`pass_ms`, a JSON object of label → ms).
fn passes(r: &Rec) -> Vec<(String, f64)> {
    let Ok(serde_json::Value::Object(m)) = serde_json::from_str(r.get(cols::PASS_MS)) else {
        return Vec::new();
    };
    m.into_iter()
        .filter_map(|(k, v)| v.as_f64().filter(|x| x.is_finite()).map(|x| (k, x)))
        .collect()
}

/// A row's slowest pass: (label, ms, share of the summed passes), from `pass_ms`.
pub fn slowest_pass(r: &Rec) -> Option<(String, f64, f64)> {
    let ps = passes(r);
    let total: f64 = ps.iter().map(|p| p.1).sum();
    let (pass, ms) = ps.into_iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some((pass, ms, if total > 0.0 { ms / total } else { 0.0 }))
}

/// The study, scene, resolution key of a row (its floors share it).
fn place(r: &Rec) -> (String, String, String) {
    (
        r.get(cols::STUDY).to_string(),
        r.get(cols::SCENE_LABEL).to_string(),
        resolution(r),
    )
}

/// Every point's bound, in the run's row order. Floors, rows not ok, rows whose GPU time is not
/// trusted and rows with no per-pass times are left out.
pub fn bounds(runs: &Runs) -> Vec<Bound> {
    let mut floors: BTreeMap<(String, String, String), f64> = BTreeMap::new();
    for r in &runs.rows {
        if r.ok() && r.get(cols::METHOD) == FLOOR_DEPTH {
            if let Some(ms) = r.trusted_ms() {
                floors.entry(place(r)).or_insert(ms);
            }
        }
    }
    let mut out = Vec::new();
    for r in &runs.rows {
        if !r.ok() || r.is_floor() {
            continue;
        }
        let Some(gpu_ms) = r.trusted_ms() else {
            continue;
        };
        let Some((pass, pass_ms, share)) = slowest_pass(r) else {
            continue;
        };
        let axes = r
            .get(cols::POINT_KEY)
            .parse::<PointKey>()
            .map(|k| k.axes)
            .unwrap_or_default();
        let method = r.get(cols::METHOD);
        let config = if axes.is_empty() {
            method.to_string()
        } else {
            format!("{method} ({axes})")
        };
        let (study, scene, resolution) = place(r);
        out.push(Bound {
            floor_ms: floors
                .get(&(study.clone(), scene.clone(), resolution.clone()))
                .copied(),
            study,
            scene,
            resolution,
            config,
            gpu_ms,
            pass,
            pass_ms,
            share,
            fragments_per_s: r.f(cols::FRAGMENTS_PER_S),
            bytes_per_s: r.f(cols::BYTES_PER_S),
            peak_frac: r.f(cols::PEAK_BANDWIDTH_FRAC),
            l2_resident: match r.get(cols::L2_RESIDENT) {
                "true" => Some(true),
                "false" => Some(false),
                _ => None,
            },
        });
    }
    out
}

const HEAD: [&str; 8] = [
    "scene",
    "resolution",
    "configuration",
    "GPU ms",
    "slowest pass (ms, share)",
    "G fragments/s",
    "GB/s declared",
    "bound",
];

fn cells(b: &Bound) -> [String; 8] {
    [
        b.scene.clone(),
        b.resolution.clone(),
        b.config.clone(),
        short(Some(b.gpu_ms)),
        format!(
            "{} ({}, {} %)",
            b.pass,
            short(Some(b.pass_ms)),
            short(Some(100.0 * b.share))
        ),
        short(b.fragments_per_s.map(|x| x / 1e9)),
        short(b.bytes_per_s.map(|x| x / 1e9)),
        b.verdict(),
    ]
}

/// The bounds as a markdown table per study (for RUN.md); "" when no row has per-pass times.
pub fn markdown(runs: &Runs) -> String {
    let all = bounds(runs);
    let mut s = String::new();
    let mut studies: Vec<&str> = all.iter().map(|b| b.study.as_str()).collect();
    studies.dedup();
    for study in studies {
        let _ = writeln!(s, "### What bounds each point: {study}\n");
        let _ = writeln!(s, "| {} |", HEAD.join(" | "));
        let _ = writeln!(s, "|{}", "---|".repeat(HEAD.len()));
        for b in all.iter().filter(|b| b.study == study) {
            let c = cells(b).map(|c| c.replace('|', "\\|"));
            let _ = writeln!(s, "| {} |", c.join(" | "));
        }
        s.push('\n');
    }
    s
}

/// The bounds as an HTML section, folded (the table is long); "" when no row has per-pass times.
pub fn section(runs: &Runs) -> maud::Markup {
    let all = bounds(runs);
    if all.is_empty() {
        return maud::html! {};
    }
    maud::html! {
        h2 id="bounds" { "What bounds each method" }
        p {
            "Per point: the slowest pass (" code { "pass_ms" } "), how it compares with the \
             depth-only floor of the same scene and resolution (within " (AT_FLOOR) "×: near it, \
             costing about what rasterising the scene once costs, whatever the pass does), and \
             the frame's declared traffic against the adapter's peak memory bandwidth (NVML). \
             Also in " code { "bounds.md" } "."
        }
        details {
            summary { (all.len()) " points" }
            table {
                tr { @for h in HEAD { th { (h) } } }
                @for b in &all { tr { @for c in cells(b) { td { (c) } } } }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use schema::Status;

    fn row(method: &str, ms: &str, pass_ms: &str, peak: &str) -> Rec {
        Rec::of(&[
            (cols::STATUS, Status::Ok.name()),
            (cols::STUDY, "methods"),
            (cols::SCENE_LABEL, "quads(n=2)"),
            (cols::WIDTH, "512"),
            (cols::HEIGHT, "512"),
            (cols::METHOD, method),
            (
                cols::POINT_KEY,
                &format!("methods|quads(n=2)|512x512|{method}|layers=8"),
            ),
            (cols::GPU_MS_MEDIAN, ms),
            (cols::PASS_MS, pass_ms),
            (cols::PEAK_BANDWIDTH_FRAC, peak),
            (cols::GPU_TIME_TRUSTED, "true"),
        ])
    }

    fn runs(rows: Vec<Rec>) -> Runs {
        Runs {
            rows,
            ..Default::default()
        }
    }

    #[test]
    fn names_the_slowest_pass_and_its_distance_from_floor_and_memory() {
        let r = runs(vec![
            row("floor_depth", "1.0", "{\"floor\":1.0}", "0.001"),
            row(
                "bdp",
                "3.0",
                "{\"depth range\":1.1,\"route\":1.8,\"resolve\":0.1}",
                "0.01",
            ),
        ]);
        let b = bounds(&r);
        assert_eq!(b.len(), 1, "floors are not bounded points");
        assert_eq!(b[0].pass, "route");
        assert!((b[0].share - 0.6).abs() < 1e-9);
        assert_eq!(b[0].config, "bdp (layers=8)");
        let v = b[0].verdict();
        assert!(v.contains("1.8× the depth-only floor"), "{v}");
        assert!(v.contains("100× from the memory bound"), "{v}");
        assert!(v.contains("of peak bandwidth"), "no roofs measured: {v}");
        // A run with measured roofs names the one the row is read against.
        let mut l2 = r.rows[1].clone();
        l2.set(cols::L2_RESIDENT, "true");
        let v = bounds(&runs(vec![r.rows[0].clone(), l2]))
            .remove(0)
            .verdict();
        assert!(v.contains("1 % of the measured L2 roof"), "{v}");
    }

    #[test]
    fn a_pass_near_the_floor_is_said_to_be_near_it() {
        let r = runs(vec![
            row("floor_depth", "1.0", "{\"floor\":1.0}", ""),
            row("bdp", "1.3", "{\"depth range\":1.1,\"route\":0.2}", ""),
        ]);
        let v = bounds(&r)[0].verdict();
        assert!(v.starts_with("near the depth-only floor (1.1× it)"), "{v}");
        assert!(v.contains("peak bandwidth unknown"), "{v}");
    }

    #[test]
    fn untrusted_or_failed_or_passless_rows_are_left_out() {
        let mut untrusted = row("compute_abuffer", "3.0", "{\"count\":1.0}", "");
        untrusted.set(cols::GPU_TIME_TRUSTED, "false");
        let mut failed = row("linked_list", "3.0", "{\"count\":1.0}", "");
        failed.set(cols::STATUS, Status::Failed.name());
        let passless = row("wboit", "3.0", "", "");
        let r = runs(vec![untrusted, failed, passless]);
        assert!(bounds(&r).is_empty());
        assert_eq!(markdown(&r), "");
        assert_eq!(section(&r).into_string(), "");
    }

    #[test]
    fn markdown_has_one_table_row_per_point() {
        let r = runs(vec![
            row("bdp", "3.0", "{\"route\":1.8}", ""),
            row("adp", "4.0", "{\"route\":2.0,\"histogram\":1.0}", ""),
        ]);
        let md = markdown(&r);
        assert_eq!(
            md.lines().filter(|l| l.starts_with("| quads")).count(),
            2,
            "{md}"
        );
    }
}
