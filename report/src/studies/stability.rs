//! Figures of the `stability` study (issue 5): per case, error vs the case's stiffness parameter
//! per method configuration; and, from the `methods` study, the specialisation speedup (uber GPU
//! time over specialised) per effect.

use schema::cols;
use schema::StudyKind;
use std::path::Path;

use anyhow::Result;

use super::methods::{config_series, Styles};
use crate::charts::{Bars, Figure, Pt, XY};
use crate::labels::{file_safe, scene_name, ConfigLabels};
use mfx_analysis::data::{Rec, Runs};

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let rows: Vec<&Rec> = runs
        .study(StudyKind::Stability)
        .into_iter()
        .filter(|r| r.ok() && !r.is_floor())
        .collect();
    let styles = Styles::new(rows.iter().copied());
    let mut figs = Vec::new();
    for case in Runs::distinct(rows.iter().copied(), cols::STABILITY_CASE) {
        let g: Vec<&Rec> = rows
            .iter()
            .copied()
            .filter(|r| r.get(cols::STABILITY_CASE) == case)
            .collect();
        let stiffness = g
            .first()
            .map(|r| r.get(cols::STIFFNESS).to_string())
            .unwrap_or_default();
        let labels = ConfigLabels::new(g.iter().copied());
        let pt = |r: &Rec| {
            Some(Pt::new(r.f(cols::STIFFNESS_VALUE)?, r.f(cols::RMSE)?).flagged(r.flagged()))
        };
        // A series per method configuration and depth convention (reversed-Z is a scene
        // parameter, so it is folded into the name from the scene label).
        let mut series = Vec::new();
        if g.iter()
            .any(|r| r.get(cols::SCENE_LABEL).contains("reversed_z=true"))
        {
            for rev in [false, true] {
                let sub: Vec<&Rec> = g
                    .iter()
                    .copied()
                    .filter(|r| r.get(cols::SCENE_LABEL).contains("reversed_z=true") == rev)
                    .collect();
                for mut s in config_series(&sub, &labels, &styles, pt) {
                    s.name = format!(
                        "{} [{}]",
                        s.name,
                        if rev { "reversed-Z" } else { "standard Z" }
                    );
                    // Reversed-Z keeps the method's marker and takes the next colour.
                    s.color = s.color.map(|c| c * 2 + rev as usize);
                    series.push(s);
                }
            }
        } else {
            series = config_series(&g, &labels, &styles, pt);
        }
        let positive_x = g
            .iter()
            .all(|r| r.f(cols::STIFFNESS_VALUE).is_some_and(|v| v > 0.0));
        let xy = XY {
            title: format!("Error vs stiffness — {case}"),
            x_label: stiffness.clone(),
            y_label: "RMSE vs ground truth".into(),
            log_x: positive_x,
            log_y: true,
            lines: true,
            series,
            zero_label: "exact (0)".into(),
            ..Default::default()
        };
        let flagged: Vec<String> = g
            .iter()
            .filter(|r| r.flagged())
            .map(|r| {
                format!(
                    "{} {} ({} = {})",
                    r.get(cols::METHOD),
                    r.flags().join("|"),
                    stiffness,
                    r.get(cols::STIFFNESS_VALUE)
                )
            })
            .collect();
        let scenes = Runs::distinct(g.iter().copied(), cols::SCENE_LABEL);
        let caption = format!(
            "Zero error is drawn in the band under the log axis. Hollow: flagged ({}). Scenes: {}. {}",
            if flagged.is_empty() {
                "none".to_string()
            } else {
                flagged.join(", ")
            },
            scenes.iter().map(|s| scene_name(s)).collect::<Vec<_>>().join("; "),
            labels.fixed_note()
        );
        figs.push(xy.draw(dir, &format!("stability_{}", file_safe(&case)), &caption)?);
    }
    figs.extend(specialisation(runs, dir)?);
    Ok(figs)
}

/// Uber over specialised GPU time for every (scene, effect, other axes) pair present.
fn specialisation(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let rows: Vec<&Rec> = runs
        .study(StudyKind::Methods)
        .into_iter()
        .filter(|r| r.ok() && !r.get(cols::SPECIALISATION).is_empty())
        .collect();
    let key = |r: &Rec| {
        format!(
            "{} — {} {}x{}{}",
            r.get(cols::METHOD),
            scene_name(r.get(cols::SCENE_LABEL)),
            r.get(cols::WIDTH),
            r.get(cols::HEIGHT),
            if r.get(cols::OCCLUSION_STOP).is_empty() {
                String::new()
            } else {
                format!(", occlusion_stop={}", r.get(cols::OCCLUSION_STOP))
            }
        )
    };
    let effects = Runs::distinct(rows.iter().copied(), cols::EFFECT);
    let mut cats: Vec<String> = Vec::new();
    for r in &rows {
        let k = key(r);
        if !cats.contains(&k) {
            cats.push(k);
        }
    }
    let series: Vec<(String, Vec<Option<Pt>>)> = effects
        .iter()
        .map(|e| {
            let vals = cats
                .iter()
                .map(|c| {
                    let find = |s: &str| {
                        rows.iter()
                            .find(|r| {
                                &key(r) == c
                                    && r.get(cols::EFFECT) == e
                                    && r.get(cols::SPECIALISATION) == s
                            })
                            .and_then(|r| r.trusted_ms())
                    };
                    match (find("uber"), find("specialised")) {
                        (Some(u), Some(s)) if s > 0.0 => Some(Pt::new(0.0, u / s)),
                        _ => None,
                    }
                })
                .collect();
            (e.clone(), vals)
        })
        .filter(|(_, v): &(String, Vec<Option<Pt>>)| v.iter().any(|p| p.is_some()))
        .collect();
    if series.is_empty() {
        return Ok(Vec::new());
    }
    let bars = Bars {
        title: "Specialisation speedup (uber / specialised GPU time)".into(),
        y_label: "speedup (×)".into(),
        log_y: false,
        categories: cats,
        series,
        reference: Some(1.0),
    };
    Ok(vec![bars.draw(
        dir,
        "effects_specialisation_speedup",
        "Uber: every attribute fetched and colour, normal, view depth and id stored per layer; specialised: only what the effect reads. Same scene, resolution, run; the line marks 1×.",
    )?])
}
