//! What the run found, written from the rows: per scene the fastest exact configuration and its
//! multiple of the floor, the fastest under each error budget, the flagged points, and what did
//! not run. `summary_text` is the text both the report's summary section and the end of
//! `mfx sweep` show.

use schema::{cols, Col};
use std::collections::BTreeMap;
use std::fmt::Write;

use crate::cells::{short, time_cell};
use crate::data::{platform, platforms, resolution, Rec, Runs};
use crate::labels::{scene_name, ConfigLabels};

/// RMSE budgets (vs the ground truth) the summary names the fastest configuration under.
pub const BUDGETS: [f64; 2] = [1e-3, 1e-2];

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

/// Studies whose rows carry an image error vs the ground truth (`rmse`).
const IMAGE_STUDIES: [&str; 2] = ["methods", "stability"];

/// The error column other studies are judged by, when they have one.
fn error_col(study: &str) -> Option<Col> {
    match study {
        "shadows" => Some(cols::VIS_RMSE),
        "deferred" | "prepass" => Some(cols::RMSE),
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

fn named(labels: &ConfigLabels, r: &Rec) -> String {
    labels.get(r)
}

fn timed(r: &Rec) -> bool {
    r.f(cols::GPU_MS_MEDIAN).is_some() && !r.flags().contains(&"timestamps_incomplete")
}

fn fastest<'a>(rows: impl Iterator<Item = &'a Rec>) -> Option<&'a Rec> {
    rows.filter(|r| timed(r)).min_by(|a, b| {
        a.f(cols::GPU_MS_MEDIAN)
            .unwrap()
            .total_cmp(&b.f(cols::GPU_MS_MEDIAN).unwrap())
    })
}

fn flag_note(r: &Rec) -> String {
    if r.flagged() {
        format!(" (flagged: {})", r.flags().join(", "))
    } else {
        String::new()
    }
}

/// One scene of an image study: fastest exact, fastest under each budget, flags.
fn image_scene(out: &mut String, rows: &[&Rec], floors: &[&Rec], labels: &ConfigLabels) {
    let exact = fastest(
        rows.iter()
            .copied()
            .filter(|r| r.exact_result() == Some(true)),
    );
    let floor = floors.iter().find(|r| r.get(cols::METHOD) == "floor_depth");
    match exact {
        Some(r) => {
            let _ = writeln!(
                out,
                "- Fastest exact: {} at {} ms, {}× floor_depth{}.",
                named(labels, r),
                time_cell(r),
                short(r.f(cols::X_FLOOR)),
                floor
                    .and_then(|f| f.f(cols::GPU_MS_MEDIAN))
                    .map(|f| format!(" ({} ms)", short(Some(f))))
                    .unwrap_or_default()
            );
        }
        None => {
            let best = rows
                .iter()
                .filter(|r| r.f(cols::RMSE).is_some())
                .min_by(|a, b| {
                    a.f(cols::RMSE)
                        .unwrap()
                        .total_cmp(&b.f(cols::RMSE).unwrap())
                });
            let _ = writeln!(
                out,
                "- No configuration was exact{}.",
                best.map(|r| format!(
                    "; the smallest error: {}, RMSE {}{}",
                    named(labels, r),
                    short(r.f(cols::RMSE)),
                    flag_note(r)
                ))
                .unwrap_or_default()
            );
        }
    }
    let exact_ms = exact.and_then(|r| r.f(cols::GPU_MS_MEDIAN));
    // Budgets whose fastest configuration is the same one share a line.
    let mut lines: Vec<(Vec<f64>, String)> = Vec::new();
    for b in BUDGETS {
        let within = fastest(
            rows.iter()
                .copied()
                .filter(|r| r.f(cols::RMSE).is_some_and(|e| e <= b)),
        );
        let text = match within {
            Some(r) if exact.is_some_and(|e| std::ptr::eq(e, r)) => {
                "the fastest exact (nothing inexact within it is faster).".to_string()
            }
            Some(r) => {
                let ms = r.f(cols::GPU_MS_MEDIAN).unwrap();
                let vs = match exact_ms {
                    Some(e) if ms < e => {
                        format!(", {}× faster than the fastest exact", short(Some(e / ms)))
                    }
                    _ => String::new(),
                };
                format!(
                    "{} at {} ms, RMSE {}{vs}{}.",
                    named(labels, r),
                    time_cell(r),
                    short(r.f(cols::RMSE)),
                    flag_note(r)
                )
            }
            None => "no configuration.".to_string(),
        };
        match lines.iter_mut().find(|(_, t)| *t == text) {
            Some((bs, _)) => bs.push(b),
            None => lines.push((vec![b], text)),
        }
    }
    for (bs, text) in lines {
        let budgets: Vec<String> = bs.iter().map(|b| format!("≤ {b:.0e}")).collect();
        let _ = writeln!(out, "- RMSE {}: {text}", budgets.join(" and "));
    }
    let flagged: Vec<&&Rec> = rows.iter().filter(|r| r.flagged()).collect();
    if !flagged.is_empty() {
        let _ = writeln!(
            out,
            "- Flagged: {} of {} ({}).",
            flagged.len(),
            rows.len(),
            count_by(flagged.iter().flat_map(|r| r.flags()))
        );
    }
}

/// Which configuration was the fastest exact one how often, over the study's scenes.
fn overall(out: &mut String, methods: &[&Rec], labels: &ConfigLabels) {
    let groups = Runs::group_by(methods.iter().copied(), |r| {
        format!("{}\u{0}{}", r.get(cols::SCENE_LABEL), resolution(r))
    });
    if groups.len() < 2 {
        return;
    }
    let mut wins: Vec<String> = Vec::new();
    let mut none = 0;
    for (_, g) in &groups {
        match fastest(g.iter().copied().filter(|r| r.exact_result() == Some(true))) {
            Some(r) => wins.push(r.get(cols::METHOD).to_string()),
            None => none += 1,
        }
    }
    let _ = labels;
    let mut line = format!(
        "Over {} scene × resolution groups, the fastest exact method: ",
        groups.len()
    );
    let tally = count_by(wins.iter().map(|s| s.as_str()));
    line.push_str(&if wins.is_empty() {
        "none".to_string()
    } else {
        // "compute_abuffer 6, linked_list 1" → "compute_abuffer in 6, linked_list in 1"
        tally
            .split(", ")
            .map(|t| match t.rsplit_once(' ') {
                Some((m, n)) => format!("{m} in {n}"),
                None => t.to_string(),
            })
            .collect::<Vec<_>>()
            .join(", ")
    });
    if none > 0 {
        line.push_str(&format!("; no exact configuration in {none}"));
    }
    let _ = writeln!(out, "{line}.\n");
}

/// One scene of another study: its fastest configuration and, with an error column, its most
/// accurate one.
fn other_scene(out: &mut String, study: &str, rows: &[&Rec], labels: &ConfigLabels) {
    if let Some(r) = fastest(rows.iter().copied()) {
        let _ = writeln!(
            out,
            "- Fastest: {} at {} ms.",
            named(labels, r),
            time_cell(r)
        );
    }
    if let Some(col) = error_col(study) {
        let best = rows
            .iter()
            .filter(|r| r.f(col).is_some())
            .min_by(|a, b| a.f(col).unwrap().total_cmp(&b.f(col).unwrap()));
        if let Some(r) = best {
            let _ = writeln!(
                out,
                "- Lowest {col}: {} ({}) at {} ms.",
                named(labels, r),
                short(r.f(col)),
                time_cell(r)
            );
        }
    }
    let flagged: Vec<&&Rec> = rows.iter().filter(|r| r.flagged()).collect();
    if !flagged.is_empty() {
        let _ = writeln!(
            out,
            "- Flagged: {} of {} ({}).",
            flagged.len(),
            rows.len(),
            count_by(flagged.iter().flat_map(|r| r.flags()))
        );
    }
}

fn platform_summary(out: &mut String, runs: &Runs, rows: &[&Rec]) {
    let mut studies: Vec<String> = Vec::new();
    for r in rows {
        let s = r.get(cols::STUDY).to_string();
        if !studies.contains(&s) {
            studies.push(s);
        }
    }
    for study in studies {
        let of: Vec<&Rec> = rows
            .iter()
            .copied()
            .filter(|r| r.get(cols::STUDY) == study)
            .collect();
        let ok: Vec<&Rec> = of.iter().copied().filter(|r| r.ok()).collect();
        let methods: Vec<&Rec> = ok.iter().copied().filter(|r| !r.is_floor()).collect();
        let labels = ConfigLabels::new(methods.iter().copied());
        let _ = writeln!(out, "\n### {study}\n");
        if methods.is_empty() {
            let _ = writeln!(
                out,
                "No measured configuration (only floors, or nothing ran)."
            );
        }
        if IMAGE_STUDIES.contains(&study.as_str()) {
            overall(out, &methods, &labels);
        }
        let effects = Runs::distinct(methods.iter().copied(), cols::EFFECT).len() > 1;
        for (key, g) in Runs::group_by(methods.iter().copied(), |r| {
            let e = if effects { r.get(cols::EFFECT) } else { "" };
            format!("{}\u{0}{}\u{0}{e}", r.get(cols::SCENE_LABEL), resolution(r))
        }) {
            let mut parts = key.split('\u{0}');
            let (label, res, effect) = (
                parts.next().unwrap_or(""),
                parts.next().unwrap_or(""),
                parts.next().unwrap_or(""),
            );
            let what = if effect.is_empty() {
                String::new()
            } else {
                format!(", {effect}")
            };
            let _ = writeln!(out, "\n{}{what}, {res}:", scene_name(label));
            if IMAGE_STUDIES.contains(&study.as_str())
                && g.iter().any(|r| r.f(cols::RMSE).is_some())
            {
                let floors: Vec<&Rec> = ok
                    .iter()
                    .copied()
                    .filter(|r| {
                        r.is_floor() && r.get(cols::SCENE_LABEL) == label && resolution(r) == res
                    })
                    .collect();
                image_scene(out, &g, &floors, &labels);
            } else {
                other_scene(out, &study, &g, &labels);
            }
        }
        let fixed = labels.fixed_note();
        if !fixed.is_empty() {
            let _ = writeln!(out, "\n{fixed}");
        }
    }
    let _ = runs;
}

/// The summary of a run (plain text, Markdown-flavoured): what it found, per platform, study and
/// scene, then what did not run and which columns this CSV does not have.
pub fn summary_text(runs: &Runs) -> String {
    let mut out = String::new();
    let count = |s: &str| {
        runs.rows
            .iter()
            .filter(|r| r.get(cols::STATUS) == s)
            .count()
    };
    let mut ids: Vec<&str> = Vec::new();
    for r in &runs.rows {
        if !ids.contains(&r.get(cols::RUN_ID)) {
            ids.push(r.get(cols::RUN_ID));
        }
    }
    let plats = platforms(runs);
    let _ = writeln!(out, "## Summary\n");
    let _ = writeln!(
        out,
        "{} rows from {} ({}): {} ok, {} skipped, {} failed.",
        runs.rows.len(),
        if ids.len() == 1 {
            format!("run {}", ids[0])
        } else {
            format!("{} runs", ids.len())
        },
        plats.join("; "),
        count("ok"),
        count("skipped"),
        count("failed")
    );
    if runs.rows.iter().any(|r| r.f(cols::RMSE).is_some()) {
        let _ = writeln!(
            out,
            "Errors are RMSE vs the ground truth; {}. Times are median GPU ms per frame [95 % CI when measured]; × floor_depth divides by the depth-only pass of the same scene.",
            runs.exactness_rule()
        );
    }
    for p in &plats {
        let rows: Vec<&Rec> = runs.rows.iter().filter(|r| platform(r) == *p).collect();
        if plats.len() > 1 {
            let _ = writeln!(out, "\n## {p}");
        }
        platform_summary(&mut out, runs, &rows);
    }
    let _ = writeln!(out, "\n### Not run\n");
    let mut any = false;
    for status in ["skipped", "failed"] {
        let rows: Vec<&Rec> = runs
            .rows
            .iter()
            .filter(|r| r.get(cols::STATUS) == status)
            .collect();
        if rows.is_empty() {
            continue;
        }
        any = true;
        let _ = writeln!(out, "- {status}: {} point(s):", rows.len());
        let mut reasons: Vec<(String, Vec<&Rec>)> = Vec::new();
        for r in &rows {
            let why = r.get(cols::REASON).to_string();
            match reasons.iter_mut().find(|(w, _)| *w == why) {
                Some((_, v)) => v.push(r),
                None => reasons.push((why, vec![r])),
            }
        }
        for (why, rs) in reasons {
            let mut methods: Vec<&str> = rs.iter().map(|r| r.get(cols::METHOD)).collect();
            methods.dedup();
            let _ = writeln!(
                out,
                "  - {} × {} ({}): {}",
                rs.len(),
                methods.join(", "),
                rs.first().map(|r| r.get(cols::STUDY)).unwrap_or(""),
                if why.is_empty() {
                    "no reason given"
                } else {
                    &why
                }
            );
        }
    }
    if !any {
        let _ = writeln!(out, "Every point ran.");
    }
    let missing: Vec<String> = NEWER
        .iter()
        .filter(|(c, _)| !runs.has(*c))
        .map(|(c, what)| format!("{c} ({what})"))
        .collect();
    if !missing.is_empty() {
        let _ = writeln!(
            out,
            "\nNot measured in this CSV (an older schema): {}.",
            missing.join("; ")
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn runs(rows: &[&str]) -> Runs {
        let header = "schema,run_id,study,scene_label,width,height,method,point_key,adapter,backend,status,reason,gpu_ms_median,x_floor,rmse,bad_pixel_frac,flag";
        let d =
            std::env::temp_dir().join(format!("mfx-summary-{}-{}", rows.len(), std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("runs.csv");
        std::fs::write(&p, format!("{header}\n{}\n", rows.join("\n"))).unwrap();
        Runs::load(&p).unwrap()
    }

    #[test]
    fn the_summary_names_the_fastest_exact_and_the_budgets() {
        let r = runs(&[
            "1,r,methods,q(d=8),64,64,floor_depth,methods|q(d=8)|64x64|floor_depth|,G,vulkan,ok,,0.1,,,,",
            "1,r,methods,q(d=8),64,64,depth_peel,methods|q(d=8)|64x64|depth_peel|max_layers=64,G,vulkan,ok,,2.0,20,0,0,",
            "1,r,methods,q(d=8),64,64,linked_list,methods|q(d=8)|64x64|linked_list|layers=8,G,vulkan,ok,,1.0,10,0,0,",
            "1,r,methods,q(d=8),64,64,kbuffer,methods|q(d=8)|64x64|kbuffer|layers=4,G,vulkan,ok,,0.25,2.5,5e-4,0.01,hazard",
            "1,r,methods,q(d=8),64,64,wboit,methods|q(d=8)|64x64|wboit|,G,vulkan,ok,,0.2,2,5e-3,0.5,",
            "1,r,methods,q(d=8),64,64,bdp,methods|q(d=8)|64x64|bdp|,G,vulkan,skipped,needs 8 attachments,,,,,",
        ]);
        let s = summary_text(&r);
        assert!(
            s.contains("Fastest exact: linked_list at 1 ms, 10× floor_depth (0.1 ms)"),
            "{s}"
        );
        assert!(s.contains("RMSE ≤ 1e-3: kbuffer at 0.25 ms, RMSE 5e-4, 4× faster than the fastest exact (flagged: hazard)"), "{s}");
        assert!(s.contains("RMSE ≤ 1e-2: wboit at 0.2 ms"), "{s}");
        assert!(s.contains("Flagged: 1 of 4 (hazard 1)"), "{s}");
        assert!(s.contains("1 × bdp (methods): needs 8 attachments"), "{s}");
        assert!(s.contains("predates the matches_truth column"), "{s}");
        assert!(s.contains("Not measured in this CSV"), "{s}");
    }
}
