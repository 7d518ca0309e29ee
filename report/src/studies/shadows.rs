//! Figures of the `shadows` study (issue 7): layered soft shadow maps against the ray-traced
//! reference — error vs GPU time per configuration, error (and its sign: light bleeding vs
//! overshadowing) vs layers, error vs max_nspp, the bias parameters, and HSM on/off.

use schema::StudyKind;
use schema::{cols, Col};
use std::path::Path;

use anyhow::Result;

use crate::charts::{Figure, Named, Pt, Series, XY};
use crate::labels::{config_axes, file_safe, scene_name, ConfigLabels};
use crate::pareto;
use mfx_analysis::data::{Rec, Runs};

/// Which of the suite's sweeps a row belongs to, told by the axes its point key sets.
fn sweep(r: &Rec) -> (usize, &'static str) {
    let axes = config_axes(r);
    let has = |c: Col| axes.iter().any(|(k, _)| k == c.name);
    if has(cols::BIAS_MODE) || has(cols::GSCALE) || has(cols::GMAX) {
        (1, "bias sweep")
    } else if has(cols::HSM) {
        (2, "HSM sweep")
    } else {
        (0, "layers × nspp sweep")
    }
}

/// Error vs time of every configuration: colour by layers and shadow-map size, marker by sweep,
/// the Pareto front named.
fn error_vs_time(g: &[&Rec], name: &str, stem: &str, dir: &Path) -> Result<Figure> {
    let labels = ConfigLabels::new(g.iter().copied());
    let mut series: Vec<Series> = Vec::new();
    let mut keys: Vec<String> = Vec::new();
    for r in g {
        let (Some(t), Some(e)) = (r.trusted_ms(), r.f(cols::VIS_RMSE)) else {
            continue;
        };
        let (family, what) = sweep(r);
        let colour_key = format!(
            "k = {}, {}²",
            r.get(cols::LAYERS),
            r.get(cols::SHADOW_MAP_RES)
        );
        if !keys.contains(&colour_key) {
            keys.push(colour_key.clone());
        }
        let n = format!("{colour_key}, {what}");
        let (lo, hi) = r.gpu_ci().unzip();
        let p = Pt {
            x: t,
            y: e,
            xlo: lo,
            xhi: hi,
            flagged: r.flagged(),
            ..Default::default()
        };
        match series.iter_mut().find(|s| s.name == n) {
            Some(s) => s.points.push(p),
            None => series.push(Series {
                name: n,
                family,
                color: keys.iter().position(|k| *k == colour_key),
                points: vec![p],
            }),
        }
    }
    let pts: Vec<(f64, f64)> = g
        .iter()
        .map(|r| {
            (
                r.trusted_ms().unwrap_or(f64::NAN),
                r.f(cols::VIS_RMSE).unwrap_or(f64::NAN),
            )
        })
        .collect();
    let front = pareto::front(&pts)
        .into_iter()
        .map(|i| Named {
            x: pts[i].0,
            y: pts[i].1,
            text: labels
                .get(g[i])
                .trim_start_matches("layered_ssm")
                .trim()
                .to_string(),
        })
        .collect();
    XY {
        title: format!("Visibility error vs GPU time — {name}"),
        x_label: "GPU time per frame [ms]".into(),
        y_label: "visibility RMSE vs ray tracing".into(),
        log_x: true,
        log_y: true,
        series,
        front,
        front_name: "Pareto front (visibility RMSE, time)".into(),
        zero_label: "exact (0)".into(),
        ..Default::default()
    }
    .draw(
        dir,
        &format!("shadows_error_vs_time_{stem}"),
        &format!(
            "One point per configuration of every sweep of the suite (colour: layers k and shadow-map size; marker: the sweep);              the dashed line joins the configurations no other beats on both, each named. The reference is m×m stratified shadow rays per pixel              from the same G-buffer points. {} {}",
            crate::points::ci_caption_rows(g),
            labels.fixed_note()
        ),
    )
}

/// Rows of the layers × max_nspp sweep: bias, gscale, gmax and hsm not set by the suite (their
/// defaults, written to the row since schema 2, are told apart by the point key), so the bias
/// and HSM sweeps (which set them) do not mix in.
fn at_defaults(r: &Rec) -> bool {
    let given = config_axes(r);
    [cols::BIAS_MODE, cols::HSM, cols::GSCALE, cols::GMAX]
        .iter()
        .all(|c| !given.iter().any(|(k, _)| k == c.name))
        && !r.get(cols::LAYERS).is_empty()
        && !r.get(cols::MAX_NSPP).is_empty()
}

/// Groups rows into series named by `name`, points (x, y) sorted by x.
fn series(
    rows: &[&Rec],
    name: impl Fn(&Rec) -> String,
    xy: impl Fn(&Rec) -> Option<(f64, f64)>,
) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for r in rows {
        let Some((x, y)) = xy(r) else { continue };
        let n = name(r);
        match out.iter_mut().find(|s| s.name == n) {
            Some(s) => s.points.push(Pt::new(x, y)),
            None => out.push(Series::new(n, vec![Pt::new(x, y)])),
        }
    }
    for s in &mut out {
        s.points.sort_by(|a, b| a.x.total_cmp(&b.x));
    }
    out
}

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let rows: Vec<&Rec> = runs
        .study(StudyKind::Shadows)
        .into_iter()
        .filter(|r| r.ok() && r.get(cols::METHOD) == "layered_ssm")
        .collect();
    let mut figs = Vec::new();
    for label in Runs::distinct(rows.iter().copied(), cols::SCENE_LABEL) {
        let g: Vec<&Rec> = rows
            .iter()
            .copied()
            .filter(|r| r.get(cols::SCENE_LABEL) == label)
            .collect();
        let stem = file_safe(&label);
        let name = scene_name(&label);
        figs.push(error_vs_time(&g, &name, &stem, dir)?);
        let d: Vec<&Rec> = g.iter().copied().filter(|r| at_defaults(r)).collect();
        // Error vs layers: does a third layer remove most light bleeding (the thesis's claim)?
        let s = series(
            &d,
            |r| {
                format!(
                    "nspp ≤ {}, {}²",
                    r.get(cols::MAX_NSPP),
                    r.get(cols::SHADOW_MAP_RES)
                )
            },
            |r| Some((r.f(cols::LAYERS)?, r.f(cols::VIS_RMSE)?)),
        );
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("Visibility error vs layers — {name}"),
                    x_label: "shadow-map layers k".into(),
                    y_label: "visibility RMSE".into(),
                    log_x: false,
                    log_y: false,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(
                    dir,
                    &format!("shadows_error_vs_layers_{stem}"),
                    "Hybrid bias, HSM on. One line per max_nspp and shadow-map size.",
                )?,
            );
        }
        // The sign of the error vs layers: light bleeding (GPU too bright) and overshadowing.
        let mut s = Vec::new();
        for (col, what) in [
            (cols::VIS_BLEED_MEAN, "light bleeding"),
            (cols::VIS_OVERSHADOW_MEAN, "overshadowing"),
        ] {
            s.extend(series(
                &d,
                |r| {
                    format!(
                        "{what}, nspp ≤ {}, {}²",
                        r.get(cols::MAX_NSPP),
                        r.get(cols::SHADOW_MAP_RES)
                    )
                },
                |r| Some((r.f(cols::LAYERS)?, r.f(col)?)),
            ));
        }
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("Light bleeding and overshadowing vs layers — {name}"),
                    x_label: "shadow-map layers k".into(),
                    y_label: "mean of max(±(GPU − reference), 0)".into(),
                    log_x: false,
                    log_y: false,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("shadows_bleeding_vs_layers_{stem}"), "Light bleeding: GPU visibility above the reference; overshadowing: below. Hybrid bias, HSM on.")?,
            );
        }
        // Error vs samples per pixel.
        let s = series(
            &d,
            |r| {
                format!(
                    "k = {}, {}²",
                    r.get(cols::LAYERS),
                    r.get(cols::SHADOW_MAP_RES)
                )
            },
            |r| Some((r.f(cols::MAX_NSPP)?, r.f(cols::VIS_RMSE)?)),
        );
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("Visibility error vs max_nspp — {name}"),
                    x_label: "max shadow-map samples per pixel".into(),
                    y_label: "visibility RMSE".into(),
                    log_x: true,
                    log_y: false,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("shadows_error_vs_nspp_{stem}"), "Above max_nspp the search region is sampled with a stride; each sample stands for its block of texels.")?,
            );
        }
        // Bias: error vs gscale per mode and gmax.
        let b: Vec<&Rec> = g
            .iter()
            .copied()
            .filter(|r| !r.get(cols::GSCALE).is_empty())
            .collect();
        let s = series(
            &b,
            |r| format!("{}, gmax {}", r.get(cols::BIAS_MODE), r.get(cols::GMAX)),
            |r| Some((r.f(cols::GSCALE)?, r.f(cols::VIS_RMSE)?)),
        );
        if !s.is_empty() {
            figs.push(
                XY {
                    title: format!("Bias: error vs gscale — {name}"),
                    x_label: "gscale (× depth change per texel)".into(),
                    y_label: "visibility RMSE".into(),
                    log_x: true,
                    log_y: false,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("shadows_bias_{stem}"), "midpoint ignores gscale (flat lines); slope and hybrid clamp the slope bias at gmax.")?,
            );
        }
        // HSM on/off: GPU time vs max_nspp.
        let h: Vec<&Rec> = g
            .iter()
            .copied()
            .filter(|r| !r.get(cols::HSM).is_empty() && r.get(cols::GSCALE).is_empty())
            .collect();
        let s = series(
            &h,
            |r| format!("hsm {}, k = {}", r.get(cols::HSM), r.get(cols::LAYERS)),
            |r| Some((r.f(cols::MAX_NSPP)?, r.trusted_ms()?)),
        );
        if s.iter().any(|s| s.name.starts_with("hsm false")) {
            figs.push(
                XY {
                    title: format!("HSM on/off: GPU time vs max_nspp — {name}"),
                    x_label: "max shadow-map samples per pixel".into(),
                    y_label: "GPU time per frame [ms]".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("shadows_hsm_{stem}"), "The min-depth pyramid shrinks the search region before sampling; its error cost is in the error-vs-time chart.")?,
            );
        }
    }
    Ok(figs)
}
