//! Figures of the bucket methods (bdp, bdp2, adp) in the `methods` study: collision rate vs
//! depth complexity, and collision rate vs GPU time (what each bucket configuration buys).

use std::path::Path;

use anyhow::Result;

use crate::charts::{Figure, XY};
use crate::data::{resolution, Rec, Runs};

use super::methods::series_by_config;

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    // Only rows that report a collision rate: the bucket methods.
    let rows: Vec<&Rec> = runs
        .study("methods")
        .into_iter()
        .filter(|r| r.ok() && r.f("collision_rate").is_some())
        .collect();
    let mut figs = Vec::new();
    for (res, at_res) in Runs::group_by(rows.iter().copied(), resolution) {
        for (generator, g) in Runs::group_by(at_res.iter().copied(), |r| r.get("scene").into()) {
            let series = series_by_config(
                &g,
                |r| Some((r.f("depth_complexity_max")?, r.f("collision_rate")?)),
                false,
            );
            if series.iter().map(|s| s.points.len()).sum::<usize>() < 2 {
                continue;
            }
            let xy = XY {
                title: format!("Bucket collisions vs depth complexity — {generator}, {res}"),
                x_label: "true max fragments per pixel".into(),
                y_label: "collision rate (fraction of true fragments merged or lost)".into(),
                log_x: true,
                log_y: false,
                lines: true,
                series,
            };
            figs.push(xy.draw(
                dir,
                &format!("buckets_collisions_vs_layers_{generator}_{res}"),
                "Exact counts: per pixel, GPU-rasterized fragments (untimed counter pass) minus fragments the method captured.",
            )?);
        }
        let series = series_by_config(
            &at_res,
            |r| Some((r.f("gpu_ms_median")?, r.f("collision_rate")?)),
            false,
        );
        if !series.is_empty() {
            let xy = XY {
                title: format!("Bucket collisions vs GPU time — all scenes, {res}"),
                x_label: "GPU time per frame [ms]".into(),
                y_label: "collision rate".into(),
                log_x: true,
                log_y: false,
                lines: false,
                series,
            };
            figs.push(xy.draw(
                dir,
                &format!("buckets_collisions_vs_time_{res}"),
                "One point per bucket configuration and scene: lower-left is better.",
            )?);
        }
    }
    Ok(figs)
}
