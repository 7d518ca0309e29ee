//! Figures of the bucket methods (bdp, bdp2, adp) in the `methods` study: collision rate vs
//! depth complexity (per family of scenes), and collision rate vs GPU time per scene (what each
//! bucket configuration buys).

use schema::cols;
use schema::StudyKind;
use std::path::Path;

use anyhow::Result;

use super::methods::{config_series, scene_families, Styles};
use crate::charts::{Figure, Pt, XY};
use crate::labels::{file_safe, scene_name, scene_names, ConfigLabels};
use crate::points::ci_caption_rows;
use mfx_analysis::data::{resolution, Rec, Runs};

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    // Only rows that report a collision rate: the bucket methods.
    let rows: Vec<&Rec> = runs
        .study(StudyKind::Methods)
        .into_iter()
        .filter(|r| r.ok() && r.f(cols::COLLISION_RATE).is_some())
        .collect();
    let styles = Styles::new(
        runs.study(StudyKind::Methods)
            .into_iter()
            .filter(|r| r.ok() && !r.is_floor()),
    );
    let mut figs = Vec::new();
    for (res, at_res) in Runs::group_by(rows.iter().copied(), resolution) {
        let scenes = Runs::distinct(at_res.iter().copied(), cols::SCENE_LABEL);
        for (family, members) in scene_families(&scenes) {
            if members.len() < 2 {
                continue;
            }
            let g: Vec<&Rec> = at_res
                .iter()
                .copied()
                .filter(|r| members.iter().any(|m| m == r.get(cols::SCENE_LABEL)))
                .collect();
            let labels = ConfigLabels::new(g.iter().copied());
            let xy = XY {
                title: format!("Bucket collisions vs depth complexity — {family}, {res}"),
                x_label: "true max fragments per pixel".into(),
                y_label: "collision rate (fraction of true fragments merged or lost)".into(),
                log_x: true,
                lines: true,
                series: config_series(&g, &labels, &styles, |r| {
                    Some(
                        Pt::new(r.f(cols::DEPTH_COMPLEXITY_MAX)?, r.f(cols::COLLISION_RATE)?)
                            .flagged(r.flagged()),
                    )
                }),
                ..Default::default()
            };
            figs.push(xy.draw(
                dir,
                &format!("buckets_collisions_vs_complexity_{}_{res}", file_safe(&family)),
                &format!(
                    "Scenes: {}. Exact counts: per pixel, GPU-rasterized fragments (untimed counter pass) minus fragments the method captured. {}",
                    scene_names(&members).join("; "),
                    labels.fixed_note()
                ),
            )?);
        }
        // One chart per scene: a collision rate is a property of a scene, so points of
        // different scenes on one chart would read as one configuration's trade-off.
        for scene in Runs::distinct(at_res.iter().copied(), cols::SCENE_LABEL) {
            let g: Vec<&Rec> = at_res
                .iter()
                .copied()
                .filter(|r| r.get(cols::SCENE_LABEL) == scene)
                .collect();
            let labels = ConfigLabels::new(g.iter().copied());
            let xy = XY {
                title: format!(
                    "Bucket collisions vs GPU time — {}, {res}",
                    scene_name(&scene)
                ),
                x_label: "GPU time per frame [ms]".into(),
                y_label: "collision rate".into(),
                log_x: true,
                series: config_series(&g, &labels, &styles, |r| {
                    let (lo, hi) = r.gpu_ci().unzip();
                    Some(Pt {
                        x: r.trusted_ms()?,
                        y: r.f(cols::COLLISION_RATE)?,
                        xlo: lo,
                        xhi: hi,
                        flagged: r.flagged(),
                        ..Default::default()
                    })
                }),
                ..Default::default()
            };
            figs.push(xy.draw(
                dir,
                &format!("buckets_collisions_vs_time_{}_{res}", file_safe(&scene)),
                &format!(
                    "One point per bucket configuration on this scene: lower-left is better. {} {}",
                    ci_caption_rows(&g),
                    labels.fixed_note()
                ),
            )?);
        }
    }
    Ok(figs)
}
