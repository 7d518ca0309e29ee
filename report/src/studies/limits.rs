//! "Fits a browser?": per limits profile (`mfx sweep --limits`), method and resolution, whether
//! the method ran as it is, ran split over several storage bindings (with its time against the
//! unsplit run of the same point under the adapter's limits, where the runs hold one), or was
//! skipped, with the limit that ruled it out.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;
use maud::{html, Markup};
use schema::{cols, Status};

use crate::charts::Figure;
use mfx_analysis::data::{resolution, Rec, Runs};

/// The runs were made under a browser's limits, or something was split.
pub fn applies(runs: &Runs) -> bool {
    runs.rows.iter().any(|r| {
        let l = r.get(cols::LIMITS);
        (!l.is_empty() && l != "adapter") || !r.get(cols::SPLIT).is_empty()
    })
}

/// How one row of a method fared, as the table counts it.
fn outcome(r: &Rec) -> &'static str {
    match r.get(cols::STATUS).parse::<Status>() {
        Ok(Status::Ok) if r.get(cols::SPLIT).is_empty() => "runs",
        Ok(Status::Ok) => "split",
        Ok(Status::Skipped) => Status::Skipped.name(),
        _ => Status::Failed.name(),
    }
}

/// A point on one adapter and backend, whatever its limits profile.
fn same_point(r: &Rec) -> (&str, &str, &str) {
    (
        r.get(cols::ADAPTER),
        r.get(cols::BACKEND),
        r.get(cols::POINT_KEY),
    )
}

/// One cell: counts of each outcome, the splits used, the split's time against the unsplit
/// row of the same point, and every distinct skip or failure reason.
fn cell(rows: &[&Rec], unsplit: &BTreeMap<(&str, &str, &str), f64>) -> Markup {
    let mut n: BTreeMap<&str, usize> = BTreeMap::new();
    for r in rows {
        *n.entry(outcome(r)).or_default() += 1;
    }
    let mut parts: Vec<String> = [
        "runs",
        "split",
        Status::Skipped.name(),
        Status::Failed.name(),
    ]
    .iter()
    .filter_map(|o| n.get(o).map(|c| format!("{o} {c}")))
    .collect();
    let mut splits: Vec<&str> = rows.iter().map(|r| r.get(cols::SPLIT)).collect();
    splits.retain(|s| !s.is_empty());
    splits.sort();
    splits.dedup();
    if !splits.is_empty() {
        parts.push(format!("({})", splits.join(", ")));
    }
    let ratios: Vec<f64> = rows
        .iter()
        .filter(|r| !r.get(cols::SPLIT).is_empty())
        .filter_map(|r| Some(r.trusted_ms()? / unsplit.get(&same_point(r))?))
        .collect();
    if !ratios.is_empty() {
        let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
        // Three decimals: a split's cost is a few per cent or less, which `short` rounds to ×1.
        let (lo, hi) = ratios
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(l, h), &x| (l.min(x), h.max(x)));
        parts.push(if ratios.len() > 1 {
            format!(
                "×{mean:.3} of unsplit ({lo:.3}–{hi:.3}, n = {})",
                ratios.len()
            )
        } else {
            format!("×{mean:.3} of unsplit")
        });
    }
    // Each distinct reason once (a cell can hold a profile's limit and a suite's own cap).
    let mut why: Vec<&str> = Vec::new();
    for r in rows {
        let w = r.get(cols::REASON);
        let ran = matches!(r.get(cols::STATUS).parse::<Status>(), Ok(Status::Ok));
        if !ran && !w.is_empty() && !why.contains(&w) {
            why.push(w);
        }
    }
    html! {
        (parts.join(" "))
        @for w in why { br; small { (w) } }
    }
}

pub fn figures(runs: &Runs, _dir: &Path) -> Result<Vec<Figure>> {
    let rows: Vec<&Rec> = runs.rows.iter().filter(|r| !r.is_floor()).collect();
    // Unsplit times under the adapter's own limits, by point on the same adapter and backend:
    // the cost of a split.
    let unsplit: BTreeMap<(&str, &str, &str), f64> = rows
        .iter()
        .filter(|r| r.get(cols::LIMITS) == "adapter" && r.get(cols::SPLIT).is_empty())
        .filter_map(|r| Some((same_point(r), r.trusted_ms()?)))
        .collect();
    let mut out = Vec::new();
    for (profile, prow) in Runs::group_by(rows.iter().copied(), |r| {
        let l = r.get(cols::LIMITS);
        if l.is_empty() { "adapter" } else { l }.to_string()
    }) {
        // Resolutions by pixel count.
        let mut res: Vec<(u64, String)> = prow
            .iter()
            .map(|r| {
                let px = r.f(cols::WIDTH).unwrap_or(0.0) * r.f(cols::HEIGHT).unwrap_or(0.0);
                (px as u64, resolution(r))
            })
            .collect();
        res.sort();
        res.dedup();
        let res: Vec<String> = res.into_iter().map(|(_, r)| r).collect();
        let methods = Runs::group_by(prow.iter().copied(), |r| r.get(cols::METHOD).to_string());
        let html = html! {
            table {
                tr { th { "method" } @for r in &res { th { (r) } } }
                @for (method, mrows) in &methods {
                    tr {
                        td { (method) }
                        @for r in &res {
                            @let here: Vec<&Rec> =
                                mrows.iter().copied().filter(|x| &resolution(x) == r).collect();
                            td { (cell(&here, &unsplit)) }
                        }
                    }
                }
            }
        };
        let mut f = Figure::html(format!("Fits a browser? Limits profile `{profile}`"), html);
        f.stem = format!("limits-{profile}");
        f.caption = format!(
            "Per method and resolution, the rows under the `{profile}` limits profile (`mfx sweep --limits {profile}`): \
             `runs` as it is, `split` over several storage bindings (how, and its GPU time against the unsplit row of the \
             same point under the adapter's limits where the runs hold one), `skipped` with the limit named (each distinct reason shown)."
        );
        out.push(f);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use schema::Col;

    fn rec(kv: &[(Col, &str)]) -> Rec {
        Rec::of(kv)
    }

    #[test]
    fn the_table_says_runs_split_or_skipped_with_the_limit_per_resolution() {
        let base = [
            (cols::STUDY, "methods"),
            (cols::WIDTH, "512"),
            (cols::HEIGHT, "512"),
        ];
        let row = |m: &str, status: &str, split: &str, why: &str| {
            let mut r = rec(&base);
            for (k, v) in [
                (cols::METHOD, m),
                (cols::STATUS, status),
                (cols::SPLIT, split),
                (cols::REASON, why),
                (cols::LIMITS, "webgpu"),
            ] {
                r.set(k, v);
            }
            r
        };
        let runs = Runs {
            rows: vec![
                row("wboit", Status::Ok.name(), "", ""),
                row("kbuffer_atomic", Status::Ok.name(), "bindings:2", ""),
                row("mlab", Status::Skipped.name(), "", "mlab layers needs 171.6 MB in one storage binding, over WebGPU's default maxStorageBufferBindingSize of 134217728 B (128 MiB)"),
            ],
            ..Default::default()
        };
        assert!(applies(&runs));
        let f = figures(&runs, Path::new("/nonexistent")).unwrap();
        assert_eq!(f.len(), 1);
        let html = f[0].html.as_ref().map(|m| m.0.as_str()).unwrap();
        assert!(html.contains("<th>512x512</th>"), "{html}");
        assert!(html.contains("<td>wboit</td><td>runs 1</td>"), "{html}");
        assert!(html.contains("split 1 (bindings:2)"), "{html}");
        assert!(
            html.contains("skipped 1<br><small>mlab layers needs 171.6 MB"),
            "{html}"
        );
        // Merged with the unlimited run of the same points (mfx merge keeps both since the
        // limits profile is part of a row's identity): the split's cost beside it, to 3 decimals.
        let timed = |limits: &str, split: &str, key: &str, ms: &str| {
            let mut r = row("kbuffer_atomic", Status::Ok.name(), split, "");
            for (k, v) in [
                (cols::LIMITS, limits),
                (cols::POINT_KEY, key),
                (cols::GPU_MS_MEDIAN, ms),
            ] {
                r.set(k, v);
            }
            r
        };
        let merged = Runs {
            rows: vec![
                timed("adapter", "", "k16", "2.000"),
                timed("webgpu", "bindings:2", "k16", "2.040"),
                timed("adapter", "", "k32", "4.000"),
                timed("webgpu", "bindings:4", "k32", "4.000"),
            ],
            ..Default::default()
        };
        let f = figures(&merged, Path::new("/nonexistent")).unwrap();
        let web = f.iter().find(|f| f.stem == "limits-webgpu").unwrap();
        let html = web.html.as_ref().map(|m| m.0.as_str()).unwrap();
        assert!(
            html.contains("×1.010 of unsplit (1.000–1.020, n = 2)"),
            "{html}"
        );
        let adapter_only = Runs {
            rows: vec![rec(&[
                (cols::LIMITS, "adapter"),
                (cols::STATUS, Status::Ok.name()),
            ])],
            ..Default::default()
        };
        assert!(!applies(&adapter_only));
    }
}
