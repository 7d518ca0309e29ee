//! The frame-time tail and the throughput of every timed row (any study): per study and
//! resolution, p99 / median GPU time against the median (one colour and marker per scene), and a
//! table of fragments/s, bytes/s and the fraction of the adapter's peak memory bandwidth. A p95
//! or p99 is shown only with its n, and only where n ≥ `TAIL_MIN_SAMPLES` (with fewer it is the
//! largest sample, not a tail).

use std::path::Path;

use anyhow::Result;
use maud::html;
use schema::cols;

use crate::cells::short;
use crate::charts::{Figure, Pt, Series, XY};
use crate::labels::{file_safe, scene_name, ConfigLabels};
use crate::points::{TAIL_MIN_SAMPLES, TAIL_RATIO};
use mfx_analysis::data::{resolution, Rec, Runs};

/// Whether any row carries the tail columns (CSVs before them have none).
pub fn applies(runs: &Runs) -> bool {
    runs.rows
        .iter()
        .any(|r| r.ok() && r.f(cols::GPU_MS_P99).is_some())
}

/// Timed rows with a trusted median and its percentiles.
fn timed(runs: &Runs) -> Vec<&Rec> {
    runs.rows
        .iter()
        .filter(|r| {
            r.ok()
                && r.trusted_ms().is_some()
                && r.f(cols::GPU_MS_P50).is_some_and(|v| v > 0.0)
                && r.f(cols::GPU_MS_P99).is_some()
        })
        .collect()
}

/// Whether a row has enough kept samples for its p95/p99 to be a tail.
fn tail_n(r: &Rec) -> Option<usize> {
    r.samples().filter(|n| *n >= TAIL_MIN_SAMPLES)
}

/// "n = 3" or "n = 3–5": the sample counts of rows.
fn n_range(rows: &[&Rec]) -> String {
    let mut ns: Vec<usize> = rows.iter().filter_map(|r| r.samples()).collect();
    ns.sort_unstable();
    match (ns.first(), ns.last()) {
        (Some(a), Some(b)) if a == b => format!("n = {a}"),
        (Some(a), Some(b)) => format!("n = {a}–{b}"),
        _ => "n unknown".into(),
    }
}

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let rows = timed(runs);
    let mut figs = Vec::new();
    let tailed: Vec<&Rec> = rows
        .iter()
        .copied()
        .filter(|r| tail_n(r).is_some())
        .collect();
    if tailed.len() < rows.len() {
        let short: Vec<&Rec> = rows
            .iter()
            .copied()
            .filter(|r| tail_n(r).is_none())
            .collect();
        figs.push(Figure::note(
            "Frame-time tail",
            format!(
                "{} of {} timed rows have fewer than {TAIL_MIN_SAMPLES} kept samples ({}): no p95 or p99 is shown for them (with so few samples p99 is the largest sample, not a tail).",
                short.len(),
                rows.len(),
                n_range(&short)
            ),
        ));
    }
    for (key, g) in Runs::group_by(tailed.iter().copied(), |r| {
        format!("{}\u{0}{}", r.get(cols::STUDY), resolution(r))
    }) {
        let (study, res) = key.split_once('\u{0}').unwrap_or((&key, ""));
        let scenes = Runs::distinct(g.iter().copied(), cols::SCENE_LABEL);
        let series: Vec<Series> = scenes
            .iter()
            .enumerate()
            .map(|(i, s)| Series {
                name: scene_name(s),
                family: i,
                color: Some(i),
                points: g
                    .iter()
                    .filter(|r| r.get(cols::SCENE_LABEL) == s)
                    .filter_map(|r| {
                        let p50 = r.f(cols::GPU_MS_P50)?;
                        Some(Pt {
                            x: r.f(cols::GPU_MS_P99)? / p50,
                            y: p50,
                            xlo: r.f(cols::GPU_MS_P95).map(|v| v / p50),
                            xhi: r.f(cols::GPU_MS_MAX).map(|v| v / p50),
                            flagged: r.flagged(),
                            ..Default::default()
                        })
                    })
                    .collect(),
            })
            .collect();
        let n_tail = g
            .iter()
            .filter(|r| {
                r.f(cols::GPU_MS_P99)
                    .zip(r.f(cols::GPU_MS_P50))
                    .is_some_and(|(a, b)| a / b > TAIL_RATIO)
            })
            .count();
        let xy = XY {
            title: format!("Frame-time tail — {study}, {res}"),
            x_label: "p99 / median GPU time per frame".into(),
            y_label: "median GPU time per frame [ms]".into(),
            log_y: true,
            series,
            vlines: vec![(TAIL_RATIO, format!("tail line {TAIL_RATIO}×"))],
            vlines_name: "the summary's tail line (named above the plot)".into(),
            ..Default::default()
        };
        figs.push(xy.draw(
            dir,
            &format!("tail_{}_{res}", file_safe(study)),
            &format!(
                "One point per configuration and scene (colour and marker: the scene). x: the 99th percentile of the per-sample GPU time over the median; whisker from p95 to the maximum. Right of the {TAIL_RATIO}× line the summary names the row ({n_tail} here). Kept samples per row: {} (rows with fewer than {TAIL_MIN_SAMPLES} are not drawn).",
                n_range(&g)
            ),
        )?);
    }
    if let Some(t) = bound_table(&rows) {
        figs.push(Figure::html(
            "Throughput: fragments/s, bytes/s and the share of peak memory bandwidth",
            t,
        ));
    }
    Ok(figs)
}

/// Every timed row with a throughput column, highest share of peak bandwidth first.
fn bound_table(rows: &[&Rec]) -> Option<maud::Markup> {
    let mut rows: Vec<&Rec> = rows
        .iter()
        .copied()
        .filter(|r| r.f(cols::FRAGMENTS_PER_S).is_some() || r.f(cols::BYTES_PER_S).is_some())
        .collect();
    if rows.is_empty() {
        return None;
    }
    rows.sort_by(|a, b| {
        let k = |r: &Rec| r.f(cols::PEAK_BANDWIDTH_FRAC).unwrap_or(-1.0);
        k(b).total_cmp(&k(a))
    });
    let labels = ConfigLabels::new(rows.iter().copied());
    let has_peak = rows
        .iter()
        .any(|r| r.f(cols::PEAK_BANDWIDTH_FRAC).is_some());
    // No tail without its n, none under TAIL_MIN_SAMPLES.
    let ratio = |r: &Rec, c| {
        tail_n(r)
            .and(r.f(c))
            .zip(r.f(cols::GPU_MS_P50))
            .map(|(a, b)| format!("{:.3}", a / b))
            .unwrap_or_default()
    };
    Some(html! {
        p.note {
            "fragments/s: the reference's fragment count over the median GPU time; bytes/s: \
             the frame's declared traffic (not a measured count) over it; "
            @if has_peak {
                "of peak bandwidth: bytes/s over the adapter's peak (NVML)"
            } @else {
                "the adapter's peak bandwidth is not known here (no NVML), so no share of it"
            }
            ". A method near the peak is bandwidth-bound; one far below it with a high \
             fragment rate is fill- or atomic-bound. p95 and p99 are shown only for rows \
             with at least " (TAIL_MIN_SAMPLES) " kept samples (n)."
        }
        details {
            summary { (rows.len()) " rows" }
            table id="throughput" {
                tr {
                    th { "study" } th { "scene" } th { "resolution" } th { "configuration" }
                    th { "median ms" } th { "n" } th { "p95 / median" } th { "p99 / median" }
                    th { "fragments/s" } th { "GB/s" } th { "of peak bandwidth" }
                }
                @for r in &rows {
                    tr {
                        td { (r.get(cols::STUDY)) }
                        td { (scene_name(r.get(cols::SCENE_LABEL))) }
                        td { (resolution(r)) }
                        td { (labels.get(r)) }
                        td { (short(r.f(cols::GPU_MS_P50))) }
                        td { (r.samples().map(|n| n.to_string()).unwrap_or_default()) }
                        td { (ratio(r, cols::GPU_MS_P95)) }
                        td { (ratio(r, cols::GPU_MS_P99)) }
                        td { (short(r.f(cols::FRAGMENTS_PER_S))) }
                        td { (short(r.f(cols::BYTES_PER_S).map(|v| v / 1e9))) }
                        td {
                            (r.f(cols::PEAK_BANDWIDTH_FRAC)
                                .map(|v| format!("{:.1} %", v * 100.0))
                                .unwrap_or_default())
                        }
                    }
                }
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::charts::layout;

    #[test]
    fn the_tail_chart_and_the_throughput_table_are_drawn_from_the_columns() {
        let d_tmp = tempfile::Builder::new()
            .prefix("mfx-tail-")
            .tempdir()
            .unwrap();
        let d = d_tmp.path().to_path_buf();
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("runs.csv");
        let header = "schema,run_id,study,scene_label,width,height,method,point_key,adapter,backend,status,reason,gpu_ms_median,gpu_ms_p50,gpu_ms_p95,gpu_ms_p99,gpu_ms_max,fragments_per_s,bytes_per_s,peak_bandwidth_frac,samples,flag";
        let rows = [
            "1,r,methods,quads(depth_complexity=8),64,64,linked_list,a,gpu,vulkan,ok,,1.0,1.0,1.2,1.35,1.5,2e9,1e11,0.021,30,",
            "1,r,methods,quads(depth_complexity=8),64,64,depth_peel,b,gpu,vulkan,ok,,2.0,2.0,2.01,2.02,2.1,1e9,5e10,0.0104,30,",
            "1,r,methods,quads(depth_complexity=32),64,64,depth_peel,c,gpu,vulkan,ok,,4.0,4.0,4.1,4.2,4.4,2e9,6e10,0.0125,30,",
        ];
        std::fs::write(&p, format!("{header}\n{}\n", rows.join("\n"))).unwrap();
        let runs = Runs::load(&p).unwrap();
        assert!(applies(&runs));
        let figs = figures(&runs, &d).unwrap();
        let chart = figs.iter().find(|f| f.is_chart()).expect("a tail chart");
        assert!(chart.caption.contains("(1 here)"), "{}", chart.caption);
        let l: layout::Layout = serde_json::from_str(
            &std::fs::read_to_string(d.join(format!("{}.layout.json", chart.stem))).unwrap(),
        )
        .unwrap();
        assert_eq!(layout::check(&l), Ok(()));
        // One series per scene; p99 / median on x.
        assert_eq!(l.series, 2);
        assert!(l.x.data.unwrap()[1] >= 1.35 - 1e-9);
        let table = figs
            .iter()
            .find_map(|f| f.html.clone())
            .expect("a table")
            .into_string();
        assert!(
            table.contains("2.1 %") && table.contains("1.350"),
            "{table}"
        );
    }
}
