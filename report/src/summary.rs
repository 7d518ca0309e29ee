//! What the run found, as a verdict computed from the rows: per scene × resolution the fastest
//! exact configuration (with the ones statistically tied with it) and its multiple of the floor,
//! the cheapest within each RMSE budget, what was flagged, and which exact rows were left out
//! because their GPU time is not trusted. `verdicts` computes it; `summary_html` (the report's
//! first section) and `summary_text` (the end of `mfx sweep`) only write it down, so the two
//! cannot disagree with each other or with the CSV.

use schema::StudyKind;
use schema::{cols, Col, Status};
use std::collections::BTreeMap;
use std::fmt::Write;

use crate::cells::{short, time_cell};
use crate::labels::{scene_name, ConfigLabels};
use crate::points::{TAIL_MIN_SAMPLES, TAIL_RATIO};
use maud::{html, Markup};
use mfx_analysis::data::{platform, platforms, resolution, Rec, Runs};
use mfx_analysis::verdict::{fastest, verdicts, Pick, Verdict, BUDGETS, IMAGE_STUDIES};

/// Columns the report reads that older CSVs lack; each missing one is named once.
const NEWER: [(Col, &str); 5] = [
    (cols::MATCHES_TRUTH, "exactness judged directly"),
    (cols::FLIP_MEAN, "FLIP"),
    (
        cols::GPU_MS_CI_LO,
        "confidence intervals of the median time",
    ),
    (
        cols::BYTES_PER_PIXEL,
        "bytes per pixel as a column (derived from bytes_allocated here)",
    ),
    (cols::SAMPLES, "kept sample counts"),
];

/// The error column other studies are judged by, when they have one.
fn error_col(study: &str) -> Option<Col> {
    match study.parse().ok()? {
        StudyKind::Shadows => Some(cols::VIS_RMSE),
        StudyKind::Deferred | StudyKind::Prepass => Some(cols::RMSE),
        // A path's error is its worst view's: the mean would hide the view that pops.
        StudyKind::Views => Some(cols::RMSE_PATH_WORST),
        _ => None,
    }
}

fn count_by<'a>(items: impl IntoIterator<Item = &'a str>) -> String {
    let mut m: BTreeMap<&str, usize> = BTreeMap::new();
    for i in items {
        *m.entry(i).or_default() += 1;
    }
    let mut v: Vec<(&str, usize)> = m.into_iter().collect();
    v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    v.iter()
        .map(|(k, n)| format!("{k} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// "name 1.2 [1.1, 1.3] ms (tied with 2: a, b)".
fn pick_text(labels: &ConfigLabels, p: &Pick, with_error: bool) -> String {
    let mut s = format!("{} at {} ms", labels.get(p.row), time_cell(p.row));
    if with_error {
        s.push_str(&format!(", RMSE {}", short(p.row.f(cols::RMSE))));
    }
    if !p.ties.is_empty() {
        let names: Vec<String> = p.ties.iter().map(|r| labels.get(r)).collect();
        s.push_str(&format!(
            " (tied with {}: {}; their time intervals overlap)",
            p.ties.len(),
            names.join("; ")
        ));
    }
    s
}

/// The sentences of one verdict (the text and the table say the same).
struct Cells {
    exact: String,
    /// ("10×", "0.1 ms"): the multiple of floor_depth and the floor's time.
    x_floor: (String, String),
    budgets: Vec<String>,
    flagged: String,
}

fn cells(v: &Verdict, labels: &ConfigLabels) -> Cells {
    let left_out = if v.exact_untrusted.is_empty() {
        String::new()
    } else {
        let names: Vec<String> = v.exact_untrusted.iter().map(|r| labels.get(r)).collect();
        let why = Runs::distinct_strings(
            v.exact_untrusted
                .iter()
                .map(|r| mfx_analysis::verdict::untrusted_reason(r)),
        )
        .join("; ");
        format!(
            "{} exact but left out: {} ({why})",
            names.len(),
            names.join("; ")
        )
    };
    // A racy method exact only because nothing raced this time is named apart, never as the
    // fastest exact.
    let in_run = v.exact_in_run.as_ref().map(|p| {
        format!(
            "exact in this run only, not by construction (claims_exact = false): {}",
            pick_text(labels, p, false)
        )
    });
    let exact = match (&v.fastest_exact, in_run) {
        (Some(p), in_run) => {
            let mut s = pick_text(labels, p, false);
            for extra in in_run
                .iter()
                .chain(Some(&left_out).filter(|l| !l.is_empty()))
            {
                s.push_str(&format!("; {extra}"));
            }
            s
        }
        (None, Some(t)) => {
            let mut s = format!("none exact by construction; {t}");
            if !left_out.is_empty() {
                s.push_str(&format!("; {left_out}"));
            }
            s
        }
        (None, None) if !left_out.is_empty() => format!("none with a trusted time; {left_out}"),
        (None, None) => format!(
            "none exact{}",
            v.best_error
                .map(|r| format!(
                    "; smallest error {} (RMSE {}{})",
                    labels.get(r),
                    short(r.f(cols::RMSE)),
                    if r.flagged() {
                        format!(", flagged {}", r.marks().join(", "))
                    } else {
                        String::new()
                    }
                ))
                .unwrap_or_default()
        ),
    };
    let x_floor = match (&v.fastest_exact, v.floor_ms) {
        (Some(p), Some(f)) if f > 0.0 => (
            format!("{}×", short(p.row.trusted_ms().map(|t| t / f))),
            format!("{} ms", short(Some(f))),
        ),
        _ => (String::new(), String::new()),
    };
    let budgets = v
        .budgets
        .iter()
        .map(|(_, p)| match p {
            Some(p)
                if v.fastest_exact
                    .as_ref()
                    .is_some_and(|e| std::ptr::eq(e.row, p.row)) =>
            {
                "the fastest exact".to_string()
            }
            Some(p) => {
                let mut s = pick_text(labels, p, true);
                if p.row.flagged() {
                    s.push_str(&format!(" [flagged {}]", p.row.marks().join(", ")));
                }
                s
            }
            None => "none".to_string(),
        })
        .collect();
    let flagged: Vec<&&Rec> = v.rows.iter().filter(|r| r.flagged()).collect();
    let flagged = if flagged.is_empty() {
        "none".to_string()
    } else {
        format!(
            "{} of {}: {}",
            flagged.len(),
            v.rows.len(),
            count_by(flagged.iter().flat_map(|r| r.marks()))
        )
    };
    Cells {
        exact,
        x_floor,
        budgets,
        flagged,
    }
}

fn scene_title(v: &Verdict) -> String {
    if v.effect.is_empty() {
        scene_name(&v.scene)
    } else {
        format!("{}, {}", scene_name(&v.scene), v.effect)
    }
}

/// One scene of another study: its fastest configuration and, with an error column, its most
/// accurate one.
fn other_scene(study: &str, rows: &[&Rec], labels: &ConfigLabels) -> (String, String) {
    let fast = fastest(rows)
        .map(|p| pick_text(labels, &p, false))
        .unwrap_or_else(|| "no trusted time".into());
    let best = error_col(study).and_then(|col| {
        rows.iter()
            .filter(|r| r.f(col).is_some())
            .min_by(|a, b| a.f(col).unwrap().total_cmp(&b.f(col).unwrap()))
            .map(|r| format!("{col} {}: {}", short(r.f(col)), labels.get(r)))
    });
    (fast, best.unwrap_or_default())
}

/// What the run is, and the flags that cover every row of a run (said once, here).
fn preamble(runs: &Runs) -> Vec<String> {
    let count = |s: Status| runs.rows.iter().filter(|r| r.status() == Some(s)).count();
    let mut ids: Vec<&str> = Vec::new();
    for r in &runs.rows {
        if !ids.contains(&r.get(cols::RUN_ID)) {
            ids.push(r.get(cols::RUN_ID));
        }
    }
    let mut out = vec![format!(
        "{} rows from {} ({}): {} ok, {} skipped, {} failed.",
        runs.rows.len(),
        if ids.len() == 1 {
            format!("run {}", ids[0])
        } else {
            format!("{} runs", ids.len())
        },
        platforms(runs).join("; "),
        count(Status::Ok),
        count(Status::Skipped),
        count(Status::Failed)
    )];
    for sw in mfx_analysis::verdict::software(runs) {
        out.push(software_line(&sw));
    }
    let vs = verdicts(runs);
    let plats = platforms(runs).len();
    for l in mfx_analysis::verdict::left_out(&vs) {
        out.push(format!(
            "Left out of the ranking by time: {} in {} of {} verdict rows{}: {}.",
            l.method,
            l.verdicts,
            l.of,
            if plats > 1 {
                format!(" on {}", l.platform)
            } else {
                String::new()
            },
            l.reason
        ));
    }
    if vs.iter().any(|(_, v)| v.exact_in_run.is_some()) {
        out.push("\"Fastest exact\" names only configurations exact by construction (the method claims every fragment, claims_exact, and was exact here). A method that claims no exactness (a racy read-modify-write) whose capture happened to be exact in this run is named apart, \"exact in this run only\".".into());
    }
    for (id, flags) in runs.run_wide_flags() {
        out.push(format!(
            "Every timed row of run {id} is flagged {} (a property of the run, e.g. a software adapter's timer): said here once, not marked per point.",
            flags.join(", ")
        ));
    }
    if runs.rows.iter().any(|r| r.f(cols::RMSE).is_some()) {
        out.push(format!(
            "Errors are RMSE vs the ground truth; {}. Times are median GPU ms per frame with their interval: [95 % CI] where there are enough samples, else (range of the samples, n). \"Tied with N\": N others whose intervals overlap the winner's. × floor divides by floor_depth (the depth-only pass) of the same scene. Rows whose GPU timestamps miss part of the frame are never ranked by time.",
            runs.exactness_rule()
        ));
    }
    out
}

/// The first-screen line of a software adapter: what its times are, at what size and n.
fn software_line(sw: &mfx_analysis::verdict::Software) -> String {
    let n = match (sw.samples.first(), sw.samples.last()) {
        (Some(a), Some(b)) if a == b => format!("n = {a} samples per point"),
        (Some(a), Some(b)) => format!("n = {a}–{b} samples per point"),
        _ => "samples per point not recorded in this CSV".to_string(),
    };
    format!(
        "Software adapter: {} is a CPU rasteriser, not a GPU. Its times are of the CPU at {}{}, {n}: they rank the methods on this machine only and say nothing of a GPU's speed.",
        sw.adapter,
        sw.resolutions.join(", "),
        match sw.profile {
            Some(true) => " (the suite's [software] profile)",
            Some(false) => " (the suite's own sizes: no [software] profile applied)",
            None => "",
        }
    )
}

/// The skipped and failed points, grouped by reason.
fn not_run(runs: &Runs) -> Vec<String> {
    let mut out = Vec::new();
    for status in [Status::Skipped, Status::Failed] {
        let rows: Vec<&Rec> = runs
            .rows
            .iter()
            .filter(|r| r.status() == Some(status))
            .collect();
        let mut reasons: Vec<(String, Vec<&Rec>)> = Vec::new();
        for r in &rows {
            let why = r.get(cols::REASON).to_string();
            match reasons.iter_mut().find(|(w, _)| *w == why) {
                Some((_, v)) => v.push(r),
                None => reasons.push((why, vec![r])),
            }
        }
        for (why, rs) in reasons {
            // Each method once, in order of first appearance (groups repeat them).
            let mut methods: Vec<&str> = Vec::new();
            for r in &rs {
                if !methods.contains(&r.get(cols::METHOD)) {
                    methods.push(r.get(cols::METHOD));
                }
            }
            out.push(format!(
                "{status}: {} × {} ({}): {}",
                rs.len(),
                methods.join(", "),
                rs.first().map(|r| r.get(cols::STUDY)).unwrap_or(""),
                if why.is_empty() {
                    "no reason given"
                } else {
                    &why
                }
            ));
        }
    }
    out
}

fn missing_columns(runs: &Runs) -> Option<String> {
    let missing: Vec<String> = NEWER
        .iter()
        .filter(|(c, _)| !runs.has(*c))
        .map(|(c, what)| format!("{c} ({what})"))
        .collect();
    (!missing.is_empty()).then(|| {
        format!(
            "Not measured in this CSV (an older schema): {}.",
            missing.join("; ")
        )
    })
}

/// Other studies (no image error ranking): per scene, the fastest and the lowest error.
/// (scene and resolution, fastest, lowest error) of one scene of another study.
type OtherLine = (String, String, String);

fn other_studies(runs: &Runs) -> Vec<(String, String, Vec<OtherLine>)> {
    let mut out = Vec::new();
    for p in platforms(runs) {
        let rows: Vec<&Rec> = runs.rows.iter().filter(|r| platform(r) == p).collect();
        let studies = Runs::distinct(rows.iter().copied(), cols::STUDY);
        for study in studies
            .iter()
            .filter(|s| !IMAGE_STUDIES.iter().any(|k| k.name() == s.as_str()))
        {
            let methods: Vec<&Rec> = rows
                .iter()
                .copied()
                .filter(|r| r.get(cols::STUDY) == study && r.ok() && !r.is_floor())
                .collect();
            let labels = ConfigLabels::new(methods.iter().copied());
            let mut lines = Vec::new();
            for (key, g) in Runs::group_by(methods.iter().copied(), |r| {
                format!(
                    "{}, {}",
                    scene_name(r.get(cols::SCENE_LABEL)),
                    resolution(r)
                )
            }) {
                let (fast, best) = other_scene(study, &g, &labels);
                lines.push((key, fast, best));
            }
            out.push((p.clone(), study.clone(), lines));
        }
    }
    out
}

/// The rows whose per-sample GPU time has a tail (p99 > `TAIL_RATIO` × p50), worst first:
/// "tail: METHOD on SCENE, RES p99 = X ms, R× median (M ms), n = N". Only rows with at least
/// `TAIL_MIN_SAMPLES` kept samples (below that p99 is the largest sample or next to it, not a
/// tail); rows whose timestamps miss part of the frame are left out (their times are not the
/// frame's).
pub fn tail_lines(runs: &Runs) -> Vec<String> {
    let ok: Vec<&Rec> = runs.rows.iter().filter(|r| r.ok()).collect();
    let labels = ConfigLabels::new(ok.iter().copied());
    let mut tails: Vec<(f64, String)> = ok
        .iter()
        .filter(|r| r.trusted_ms().is_some())
        .filter_map(|r| {
            let n = r.samples().filter(|n| *n >= TAIL_MIN_SAMPLES)?;
            let (p50, p99) = (r.f(cols::GPU_MS_P50)?, r.f(cols::GPU_MS_P99)?);
            let ratio = p99 / p50;
            (p50 > 0.0 && ratio > TAIL_RATIO).then(|| {
                (
                    ratio,
                    format!(
                        "tail: {} on {}, {} p99 = {} ms, {:.2}× median ({} ms), n = {n}",
                        labels.get(r),
                        scene_name(r.get(cols::SCENE_LABEL)),
                        resolution(r),
                        short(Some(p99)),
                        ratio,
                        short(Some(p50))
                    ),
                )
            })
        })
        .collect();
    tails.sort_by(|a, b| b.0.total_cmp(&a.0));
    tails.into_iter().map(|(_, l)| l).collect()
}

/// The summary as HTML: the verdict table per study first, then the other studies, what did
/// not run (folded) and the columns this CSV lacks.
pub fn summary_html(runs: &Runs) -> String {
    summary_markup(runs).into_string()
}

/// `summary_html` as markup, for the page.
pub fn summary_markup(runs: &Runs) -> Markup {
    let plats = platforms(runs).len();
    let vs = verdicts(runs);
    let on = |p: &str| {
        if plats > 1 {
            format!(" — {p}")
        } else {
            String::new()
        }
    };
    let tails = tail_lines(runs);
    let nr = not_run(runs);
    html! {
        section id="summary" {
            h2 { "Verdict" }
            @for line in preamble(runs) { p.note { (line) } }
            @for (key, group) in Runs::group_by_owned(&vs, |(p, v)| format!("{p}\u{0}{}", v.study)) {
                @let (p, study) = key.split_once('\u{0}').unwrap_or((&key, ""));
                @let all: Vec<&Rec> = group.iter().flat_map(|(_, v)| v.rows.iter().copied()).collect();
                @let labels = ConfigLabels::new(all.iter().copied());
                table.verdict id={ "verdict-" (study) } {
                    caption { (study) (on(p)) ": the winner per scene × resolution" }
                    tr {
                        th { "scene" } th { "resolution" } th { "fastest exact (by construction)" }
                        th { "× floor_depth" }
                        @for b in BUDGETS { th { (format!("fastest with RMSE ≤ {b:.0e}")) } }
                        th { "flagged (not counting run-wide flags)" }
                    }
                    @for (_, v) in &group {
                        @let c = cells(v, &labels);
                        tr {
                            td { (scene_title(v)) }
                            td { (v.res) }
                            td { (c.exact) }
                            td {
                                @if !c.x_floor.0.is_empty() { (c.x_floor.0) " (" (c.x_floor.1) ")" }
                            }
                            @for b in &c.budgets { td { (b) } }
                            td { (c.flagged) }
                        }
                    }
                }
                @let fixed = labels.fixed_note();
                @if !fixed.is_empty() { p.note { (fixed) } }
            }
            @for (p, study, lines) in other_studies(runs) {
                table.verdict {
                    caption { (study) (on(&p)) }
                    tr { th { "scene, resolution" } th { "fastest" } th { "lowest error" } }
                    @for (k, f, b) in &lines { tr { td { (k) } td { (f) } td { (b) } } }
                }
            }
            @if !tails.is_empty() {
                details id="tails" open[tails.len() <= 10] {
                    summary {
                        "Frame-time tails: " (tails.len()) " row(s) with p99 > " (TAIL_RATIO)
                        "× median (rows with at least " (TAIL_MIN_SAMPLES) " samples)"
                    }
                    ul { @for l in &tails { li { (l) } } }
                }
            }
            @if nr.is_empty() {
                p.note { "Every point ran." }
            } @else {
                details {
                    summary { "Not run: " (nr.len()) " group(s) of points" }
                    ul { @for l in &nr { li { (l) } } }
                }
            }
            @if let Some(m) = missing_columns(runs) { p.note { (m) } }
        }
    }
}

/// The summary of a run as plain text (what `mfx sweep` prints at its end): the same verdicts as
/// `summary_html`, one line per scene.
pub fn summary_text(runs: &Runs) -> String {
    let mut out = String::from("Summary\n");
    for line in preamble(runs) {
        let _ = writeln!(out, "{line}");
    }
    let vs = verdicts(runs);
    for (key, group) in Runs::group_by_owned(&vs, |(p, v)| format!("{p}\u{0}{}", v.study)) {
        let (p, study) = key.split_once('\u{0}').unwrap_or((&key, ""));
        let all: Vec<&Rec> = group
            .iter()
            .flat_map(|(_, v)| v.rows.iter().copied())
            .collect();
        let labels = ConfigLabels::new(all.iter().copied());
        let _ = writeln!(out, "\n{study} ({p}):");
        for (_, v) in group {
            let c = cells(v, &labels);
            let _ = writeln!(out, "{}, {}:", scene_title(v), v.res);
            let _ = writeln!(
                out,
                "- Fastest exact (by construction): {}{}.",
                c.exact,
                if c.x_floor.0.is_empty() {
                    String::new()
                } else {
                    format!(", {} floor_depth ({})", c.x_floor.0, c.x_floor.1)
                }
            );
            for (b, t) in BUDGETS.iter().zip(&c.budgets) {
                let _ = writeln!(out, "- RMSE ≤ {b:.0e}: {t}.");
            }
            let _ = writeln!(out, "- Flagged: {}.", c.flagged);
        }
        let fixed = labels.fixed_note();
        if !fixed.is_empty() {
            let _ = writeln!(out, "{fixed}");
        }
    }
    for (p, study, lines) in other_studies(runs) {
        let _ = writeln!(out, "\n{study} ({p}):");
        for (k, f, b) in lines {
            let _ = writeln!(
                out,
                "- {k}: fastest {f}{}",
                if b.is_empty() {
                    String::new()
                } else {
                    format!("; lowest {b}")
                }
            );
        }
    }
    let tails = tail_lines(runs);
    if !tails.is_empty() {
        let _ = writeln!(out, "\nFrame-time tails (p99 > {TAIL_RATIO}× median):");
        for l in tails {
            let _ = writeln!(out, "- {l}");
        }
    }
    let nr = not_run(runs);
    let _ = writeln!(out, "\nNot run:");
    if nr.is_empty() {
        let _ = writeln!(out, "Every point ran.");
    }
    for l in nr {
        let _ = writeln!(out, "- {l}");
    }
    if let Some(m) = missing_columns(runs) {
        let _ = writeln!(out, "\n{m}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use mfx_analysis::verdict::{exact_by_construction, overlap};

    fn runs(_name: &str, rows: &[&str]) -> Runs {
        let header = "schema,run_id,study,scene_label,width,height,method,point_key,adapter,backend,status,reason,gpu_ms_median,gpu_ms_ci_lo,gpu_ms_ci_hi,samples,x_floor,rmse,bad_pixel_frac,matches_truth,exact,overflow_rate,flag";
        with_header(header, rows)
    }

    /// Rows under a header, loaded (the CSV is read whole; its folder is removed at once).
    fn with_header(header: &str, rows: &[&str]) -> Runs {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("runs.csv");
        std::fs::write(&p, format!("{header}\n{}\n", rows.join("\n"))).unwrap();
        Runs::load(&p).unwrap()
    }

    const LAVAPIPE: &str = "schema,run_id,study,scene_label,width,height,method,point_key,adapter,backend,device_type,status,reason,gpu_ms_median,gpu_ms_ci_lo,gpu_ms_ci_hi,gpu_ms_p50,gpu_ms_p99,samples,rmse,matches_truth,exact,claims_exact,exact_bound,gpu_time_trusted,flag";

    /// quads(8) at 128² on lavapipe, as issue 44 found it: the racy RMW k-buffer fastest and
    /// exact in this run, the compute A-buffer exact but untimed, 3 samples a point.
    fn lavapipe_rows() -> Runs {
        with_header(
            LAVAPIPE,
            &[
                "3,r,methods,quads(depth_complexity=8),128,128,floor_depth,k0,lavapipe,vulkan,cpu,ok,,0.5,0.4,0.6,0.5,0.6,3,,,,,,true,",
                "3,r,methods,quads(depth_complexity=8),128,128,kbuffer_rmw,k1,lavapipe,vulkan,cpu,ok,,1.0,0.9,1.1,1.0,2.0,3,3e-8,true,true,false,1e-6,true,",
                "3,r,methods,quads(depth_complexity=8),128,128,depth_peel,k2,lavapipe,vulkan,cpu,ok,,3.0,2.9,3.1,3.0,3.3,3,3e-8,true,true,true,1e-6,true,",
                "3,r,methods,quads(depth_complexity=8),128,128,compute_abuffer,k3,lavapipe,vulkan,cpu,ok,,0.2,0.1,0.3,0.2,0.3,3,3e-8,true,true,true,1e-6,false,timestamps_incomplete",
                "3,r,methods,quads(depth_complexity=8),128,128,wboit,k4,lavapipe,vulkan,cpu,ok,,0.8,0.7,0.9,0.8,0.9,3,2e-2,false,false,false,1e-6,true,",
            ],
        )
    }

    #[test]
    fn a_racy_method_exact_in_this_run_is_never_the_fastest_exact() {
        let r = lavapipe_rows();
        let (_, v) = &verdicts(&r)[0];
        assert_eq!(
            v.fastest_exact.as_ref().unwrap().row.get(cols::METHOD),
            "depth_peel"
        );
        assert_eq!(
            v.exact_in_run.as_ref().unwrap().row.get(cols::METHOD),
            "kbuffer_rmw"
        );
        let t = summary_text(&r);
        assert!(
            t.contains("Fastest exact (by construction): depth_peel")
                && t.contains("exact in this run only, not by construction (claims_exact = false): kbuffer_rmw"),
            "{t}"
        );
        let h = summary_html(&r);
        assert!(h.contains("fastest exact (by construction)"), "{h}");
        // A racy method slower than the fastest exact one is not named at all.
        assert!(check_against_rows(&r) == 1);
    }

    #[test]
    fn a_software_adapter_s_first_screen_says_what_it_is_and_what_was_left_out() {
        let t = summary_text(&lavapipe_rows());
        assert!(
            t.contains("Software adapter: lavapipe is a CPU rasteriser, not a GPU")
                && t.contains("at 128x128")
                && t.contains("n = 3 samples per point"),
            "{t}"
        );
        assert!(
            t.contains("Left out of the ranking by time: compute_abuffer in 1 of 1 verdict rows: its GPU timestamps miss part of the frame (gpu_time_trusted = false)"),
            "{t}"
        );
        // Said before the verdicts (the first screen), not only in a table cell.
        assert!(t.find("Software adapter").unwrap() < t.find("Fastest exact").unwrap());
        // No tail from 3 samples: p99 = 2× the median here is the largest sample.
        assert!(tail_lines(&lavapipe_rows()).is_empty());
        assert!(!t.contains("Frame-time tails"), "{t}");
        // A GPU run says none of it.
        let gpu = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../results/reference/2026-12-02-h200-default/default/runs.csv"
        ))
        .unwrap();
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("runs.csv"), gpu).unwrap();
        let g = summary_text(&Runs::load(&d.path().join("runs.csv")).unwrap());
        assert!(!g.contains("Software adapter"), "{g}");
    }

    /// Every winner the verdict names is what the rows say: exact rows for "fastest exact",
    /// rows within the budget for a budget, trusted times only, nothing faster left out, and
    /// every tie's interval overlapping the winner's.
    fn check_against_rows(runs: &Runs) -> usize {
        let vs = verdicts(runs);
        for (_, v) in &vs {
            let timed: Vec<&Rec> = v
                .rows
                .iter()
                .copied()
                .filter(|r| r.trusted_ms().is_some())
                .collect();
            let exact: Vec<&Rec> = timed
                .iter()
                .copied()
                .filter(|r| exact_by_construction(r))
                .collect();
            if let Some(p) = &v.fastest_exact {
                assert!(
                    exact_by_construction(p.row),
                    "{}",
                    p.row.get(cols::POINT_KEY)
                );
                assert!(p.row.time_trusted());
                let t = p.row.trusted_ms().unwrap();
                for r in &exact {
                    assert!(r.trusted_ms().unwrap() >= t, "{}", r.get(cols::POINT_KEY));
                }
                for tie in &p.ties {
                    assert!(overlap(tie, p.row) && exact_by_construction(tie));
                }
            } else {
                assert!(exact.is_empty());
            }
            // "Exact in this run" is a method that claims no exactness, faster than the
            // fastest exact by construction.
            if let Some(p) = &v.exact_in_run {
                assert!(p.row.exact_result() == Some(true) && p.row.claims_exact() == Some(false));
                if let Some(f) = &v.fastest_exact {
                    assert!(p.row.trusted_ms() < f.row.trusted_ms());
                }
            }
            for r in &v.exact_untrusted {
                assert!(r.exact_result() == Some(true) && r.trusted_ms().is_none());
            }
            for (b, p) in &v.budgets {
                let within: Vec<&Rec> = timed
                    .iter()
                    .copied()
                    .filter(|r| r.f(cols::RMSE).is_some_and(|e| e <= *b))
                    .collect();
                match p {
                    Some(p) => {
                        assert!(p.row.f(cols::RMSE).is_some_and(|e| e <= *b));
                        let t = p.row.trusted_ms().unwrap();
                        assert!(within.iter().all(|r| r.trusted_ms().unwrap() >= t));
                    }
                    None => assert!(within.is_empty()),
                }
            }
        }
        vs.len()
    }

    #[test]
    fn the_verdict_names_only_exact_trusted_fastest_rows() {
        let r = runs(
            "synthetic",
            &[
                "1,r,methods,q(d=8),64,64,floor_depth,methods|q(d=8)|64x64|floor_depth|,G,vulkan,ok,,0.1,0.09,0.11,30,,,,,,,",
                "1,r,methods,q(d=8),64,64,depth_peel,methods|q(d=8)|64x64|depth_peel|max_layers=64,G,vulkan,ok,,2.0,1.9,2.1,30,20,3e-8,0,true,true,,",
                "1,r,methods,q(d=8),64,64,linked_list,methods|q(d=8)|64x64|linked_list|layers=8,G,vulkan,ok,,1.0,0.9,1.1,30,10,3e-8,0,true,true,,",
                // Tied with the linked list: its interval overlaps.
                "1,r,methods,q(d=8),64,64,bdp,methods|q(d=8)|64x64|bdp|,G,vulkan,ok,,1.05,0.95,1.2,30,10.5,3e-8,0,true,true,,",
                // Fastest of all and exact, but its timestamps missed part of the frame.
                "1,r,methods,q(d=8),64,64,compute_abuffer,methods|q(d=8)|64x64|compute_abuffer|,G,vulkan,ok,,0.05,0.04,0.06,30,0.5,3e-8,0,true,true,,timestamps_incomplete",
                // Within tolerance (matches_truth) but overflowed: never exact.
                "1,r,methods,q(d=8),64,64,kbuffer_rmw,methods|q(d=8)|64x64|kbuffer_rmw|layers=16,G,vulkan,ok,,0.5,0.45,0.55,30,5,3.2e-4,0,true,true,0.271,overflow",
                "1,r,methods,q(d=8),64,64,wboit,methods|q(d=8)|64x64|wboit|,G,vulkan,ok,,0.2,0.19,0.21,30,2,5e-3,0.5,false,false,,",
                "1,r,methods,q(d=8),64,64,adp,methods|q(d=8)|64x64|adp|,G,vulkan,skipped,needs 8 attachments,,,,,,,,,,,",
            ],
        );
        assert_eq!(check_against_rows(&r), 1);
        let (_, v) = &verdicts(&r)[0];
        let fe = v.fastest_exact.as_ref().unwrap();
        assert_eq!(fe.row.get(cols::METHOD), "linked_list");
        assert_eq!(fe.ties.len(), 1);
        assert_eq!(v.exact_untrusted.len(), 1);
        assert_eq!(
            v.budgets[0].1.as_ref().unwrap().row.get(cols::METHOD),
            "kbuffer_rmw"
        );
        assert_eq!(
            v.budgets[1].1.as_ref().unwrap().row.get(cols::METHOD),
            "wboit"
        );
        let h = summary_html(&r);
        assert!(!h.contains("<pre"), "{h}");
        assert!(h.contains("tied with 1: bdp"), "{h}");
        assert!(h.contains("1 exact but left out: compute_abuffer"), "{h}");
        assert!(h.contains("10× (0.1 ms)"), "{h}");
        let t = summary_text(&r);
        assert!(
            t.contains("Fastest exact (by construction): linked_list"),
            "{t}"
        );
        assert!(
            t.contains("skipped: 1 × adp (methods): needs 8 attachments"),
            "{t}"
        );
    }

    #[test]
    fn exact_rows_without_timestamps_are_named_and_skipped_methods_once() {
        // The H200's GLES rows: exact, but wgpu's GLES has no timer queries.
        let r = runs(
            "untimed",
            &[
                "1,r,methods,q,64,64,linked_list,k1,H200,gl,ok,,,,,,,3e-8,0,true,true,,",
                "1,r,methods,q,64,64,bdp,k2,H200,gl,skipped,lacks FLOAT32_BLENDABLE,,,,,,,,,,,",
                "1,r,methods,q,64,64,adp,k3,H200,gl,skipped,lacks FLOAT32_BLENDABLE,,,,,,,,,,,",
                "1,r,methods,q2,64,64,bdp,k4,H200,gl,skipped,lacks FLOAT32_BLENDABLE,,,,,,,,,,,",
            ],
        );
        let t = summary_text(&r);
        assert!(!t.contains("none exact"), "{t}");
        assert!(
            t.contains("1 exact but left out: linked_list") && t.contains("no GPU time"),
            "{t}"
        );
        assert!(
            t.contains("skipped: 3 × bdp, adp (methods): lacks FLOAT32_BLENDABLE"),
            "{t}"
        );
    }

    #[test]
    fn a_three_sample_interval_is_a_range_and_a_run_wide_flag_is_said_once() {
        let r = runs(
            "range",
            &[
                "1,r,methods,q,64,64,linked_list,k1,lavapipe,vulkan,ok,,1.93,1.52,5.8,3,,3e-8,0,true,true,,noisy",
                "1,r,methods,q,64,64,depth_peel,k2,lavapipe,vulkan,ok,,1.96,1.71,6.09,3,,3e-8,0,true,true,,noisy",
            ],
        );
        let (_, v) = &verdicts(&r)[0];
        assert_eq!(v.fastest_exact.as_ref().unwrap().ties.len(), 1);
        assert!(v.rows.iter().all(|x| !x.flagged()), "noisy covers the run");
        let h = summary_html(&r);
        assert!(h.contains("range 1.52–5.8, n = 3"), "{h}");
        assert!(!h.contains("1.93 [1.52"), "{h}");
        assert!(
            h.contains("Every timed row of run r is flagged noisy"),
            "{h}"
        );
    }

    /// A committed run's rows (`results/reference/<folder>/runs.csv`).
    fn committed(folder: &str) -> Runs {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../results/reference");
        Runs::load(&root.join(folder).join("runs.csv")).unwrap()
    }

    #[test]
    fn a_committed_run_s_verdict_agrees_with_its_rows() {
        let r = committed("2026-12-02-h200-default/default");
        assert!(check_against_rows(&r) > 5);
        // No row with an overflow is named exact.
        for (_, v) in verdicts(&r) {
            if let Some(p) = v.fastest_exact {
                assert!(p.row.f(cols::OVERFLOW_RATE).is_none_or(|o| o == 0.0));
            }
        }
    }

    #[test]
    fn a_views_run_names_the_lowest_worst_view_error_of_each_path() {
        let r = committed("2026-12-06-h100-sources/views");
        let views: Vec<_> = other_studies(&r)
            .into_iter()
            .filter(|(_, study, _)| study == "views")
            .flat_map(|(_, _, lines)| lines)
            .collect();
        // Four paths (shells, grass, bunnies, teapots); the frames at rest have no path error.
        let named: Vec<_> = views
            .iter()
            .filter(|(_, _, best)| !best.is_empty())
            .collect();
        assert!(named.len() >= 4, "{views:?}");
        for (scene, _, best) in named {
            assert!(best.starts_with("rmse_path_worst "), "{scene}: {best:?}");
        }
    }

    #[test]
    fn a_tail_is_said_when_p99_exceeds_the_median_by_a_fifth_and_not_otherwise() {
        let header = "schema,run_id,study,scene_label,width,height,method,point_key,adapter,backend,status,reason,gpu_ms_median,gpu_ms_p50,gpu_ms_p95,gpu_ms_p99,samples,flag";
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let p = d.join("runs.csv");
        let rows = [
            "1,r,methods,quads(depth_complexity=8),64,64,linked_list,a,gpu,vulkan,ok,,1.0,1.0,1.2,1.35,30,",
            "1,r,methods,quads(depth_complexity=8),64,64,depth_peel,b,gpu,vulkan,ok,,2.0,2.0,2.2,2.39,30,",
            "1,r,methods,quads(depth_complexity=8),64,64,wboit,c,gpu,vulkan,ok,,3.0,3.0,3.1,3.6,30,",
        ];
        std::fs::write(&p, format!("{header}\n{}\n", rows.join("\n"))).unwrap();
        let r = Runs::load(&p).unwrap();
        let t = tail_lines(&r);
        // 1.35× is a tail; 1.195× and exactly 1.2× are not.
        assert_eq!(t.len(), 1, "{t:?}");
        assert!(
            t[0].starts_with("tail: linked_list on quads")
                && t[0].contains("p99 = 1.35 ms, 1.35× median")
                && t[0].ends_with("n = 30"),
            "{t:?}"
        );
        assert!(summary_text(&r).contains(&t[0]));
        assert!(summary_html(&r).contains("id=\"tails\""));
        // No p99 column (an older CSV): no tail line.
        let p0 = d.join("old.csv");
        std::fs::write(
            &p0,
            "schema,run_id,study,scene_label,width,height,method,point_key,adapter,backend,status,reason,gpu_ms_median,samples,flag\n1,r,methods,quads(depth_complexity=8),64,64,linked_list,a,gpu,vulkan,ok,,1.0,30,\n",
        )
        .unwrap();
        assert!(tail_lines(&Runs::load(&p0).unwrap()).is_empty());
    }
}
