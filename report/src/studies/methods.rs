//! Figures of the `methods` study: time vs layers, error vs time (Pareto), hazard / overflow /
//! collision rates vs depth complexity, speedup over classic depth peeling, and multiples of the
//! depth-only floor.

use std::path::Path;

use anyhow::Result;

use crate::charts::{Bars, Figure, Pt, Series, XY};
use crate::data::{resolution, Rec, Runs};

/// Axes that distinguish configurations of one method.
pub const CONFIG_AXES: &[&str] = &[
    "layers",
    "max_layers",
    "variant",
    "payload",
    "specialisation",
    "effect",
    "bucket_count",
    "bucket_pairing",
    "hist_bins",
    "small_max",
];

/// Errors of exact results are 0; drawn at this floor on log axes.
pub const EXACT_FLOOR: f64 = 1e-7;

fn safe(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect::<String>()
        .chars()
        .take(60)
        .collect()
}

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let rows: Vec<&Rec> = runs
        .study("methods")
        .into_iter()
        .filter(|r| r.ok())
        .collect();
    let mut figs = Vec::new();
    let methods: Vec<&Rec> = rows
        .iter()
        .copied()
        .filter(|r| !r.get("method").starts_with("floor_"))
        .collect();
    for (res, at_res) in Runs::group_by(methods.iter().copied(), resolution) {
        // Time vs layers: x = true max depth complexity of the scene, per generator.
        for (generator, g) in Runs::group_by(at_res.iter().copied(), |r| r.get("scene").into()) {
            let series = series_by_config(
                &g,
                |r| Some((r.f("depth_complexity_max")?, r.f("gpu_ms_median")?)),
                true,
            );
            if series.iter().map(|s| s.points.len()).sum::<usize>() >= 2 {
                let xy = XY {
                    title: format!("GPU time vs depth complexity — {generator}, {res}"),
                    x_label: "true max fragments per pixel".into(),
                    y_label: "GPU time per frame [ms]".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series,
                };
                figs.push(xy.draw(dir, &format!("methods_time_vs_layers_{}_{res}", safe(&generator)), "Median GPU time (whiskers: min–max over the timed repetitions) against the scene's true maximum depth complexity (CPU reference).")?);
            }
        }
        // Error vs time, per scene: the Pareto view.
        for (label, g) in Runs::group_by(at_res.iter().copied(), |r| r.get("scene_label").into()) {
            let series = series_by_config(
                &g,
                |r| Some((r.f("gpu_ms_median")?, r.f("rmse")?.max(EXACT_FLOOR))),
                false,
            );
            if series.is_empty() {
                continue;
            }
            let xy = XY {
                title: format!("Error vs time — {label}, {res}"),
                x_label: "GPU time per frame [ms]".into(),
                y_label: "RMSE vs f64 reference".into(),
                log_x: true,
                log_y: true,
                lines: false,
                series,
            };
            figs.push(xy.draw(dir, &format!("methods_error_vs_time_{}_{res}", safe(&label)), &format!("One point per method configuration. Exact results (RMSE 0) are drawn at {EXACT_FLOOR:.0e}.") )?);
        }
        // Failure rates vs depth complexity: k-buffer hazards, capacity overflow, bucket
        // collisions; one figure per rate that some configuration reports.
        for (col, what) in [
            (
                "hazard_rate",
                "pixels whose captured set is not the true k nearest (RMW hazards)",
            ),
            (
                "overflow_rate",
                "pixels whose fragments exceeded the method's capacity",
            ),
            ("collision_rate", "true fragments merged or lost by buckets"),
        ] {
            let g: Vec<&Rec> = at_res
                .iter()
                .copied()
                .filter(|r| r.f(col).is_some())
                .collect();
            let series = series_by_config(
                &g,
                |r| Some((r.f("depth_complexity_max")?, r.f(col)?)),
                false,
            );
            if series.iter().map(|s| s.points.len()).sum::<usize>() < 2 {
                continue;
            }
            let xy = XY {
                title: format!("{col} vs depth complexity — {res}"),
                x_label: "true max fragments per pixel".into(),
                y_label: format!("{col} (fraction)"),
                log_x: true,
                log_y: false,
                lines: false,
                series,
            };
            figs.push(xy.draw(
                dir,
                &format!("methods_{col}_{res}"),
                &format!("Fraction of {what}, one point per scene and configuration."),
            )?);
        }
        // Speedup over depth peeling and multiple of the floor, per scene.
        let labels = Runs::distinct(at_res.iter().copied(), "scene_label");
        let configs = Runs::distinct_configs(&at_res);
        for (col, title, ylab, stem, reference) in [
            (
                "speedup_vs_depth_peel",
                "Speedup over classic depth peeling",
                "speedup (×)",
                "methods_speedup",
                Some(1.0),
            ),
            (
                "x_floor",
                "Multiple of the depth-only floor",
                "GPU time / floor_depth time (×)",
                "methods_x_floor",
                Some(1.0),
            ),
        ] {
            let series: Vec<(String, Vec<Option<Pt>>)> = configs
                .iter()
                .map(|c| {
                    let vals = labels
                        .iter()
                        .map(|l| {
                            at_res
                                .iter()
                                .find(|r| {
                                    r.get("scene_label") == l && &r.config_label(CONFIG_AXES) == c
                                })
                                .and_then(|r| r.f(col))
                                .map(|v| Pt::new(0.0, v))
                        })
                        .collect();
                    (c.clone(), vals)
                })
                .filter(|(_, v): &(String, Vec<Option<Pt>>)| v.iter().any(|p| p.is_some()))
                .collect();
            if series.is_empty() {
                continue;
            }
            let bars = Bars {
                title: format!("{title} — {res}"),
                y_label: ylab.into(),
                log_y: true,
                categories: labels.clone(),
                series,
                reference,
            };
            figs.push(bars.draw(
                dir,
                &format!("{stem}_{res}"),
                "Same scene, resolution and run; the line marks 1×.",
            )?);
        }
    }
    Ok(figs)
}

/// One series per method configuration, points sorted by x.
pub fn series_by_config(
    rows: &[&Rec],
    xy: impl Fn(&Rec) -> Option<(f64, f64)>,
    spread: bool,
) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for r in rows {
        let Some((x, y)) = xy(r) else { continue };
        let name = r.config_label(CONFIG_AXES);
        let p = if spread {
            Pt::spread(x, y, r.f("gpu_ms_min"), r.f("gpu_ms_max"))
        } else {
            Pt::new(x, y)
        };
        match out.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(p),
            None => out.push(Series {
                name,
                points: vec![p],
            }),
        }
    }
    for s in &mut out {
        s.points.sort_by(|a, b| a.x.total_cmp(&b.x));
    }
    out
}

impl Runs {
    /// Distinct method configurations (method + config axes), first-seen order.
    pub fn distinct_configs(rows: &[&Rec]) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for r in rows {
            let c = r.config_label(CONFIG_AXES);
            if !out.contains(&c) {
                out.push(c);
            }
        }
        out
    }
}
