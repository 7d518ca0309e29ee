//! Figures of the `views` study (issue 42: views that move). Per scene, resolution and camera
//! path: flicker against GPU time over the path (one point per method configuration, its time
//! the median of its views' medians with the p99 over the views as the whisker's end; the
//! configurations no other beats on both joined as a front), then each configuration's error
//! and popping along the path, view by view (`path_series`).

use schema::cols;
use schema::StudyKind;
use std::path::Path;

use anyhow::Result;

use super::methods::{config_series, Styles};
use crate::charts::{Figure, Named, Pt, Series, XY};
use crate::data::{resolution, Rec, Runs};
use crate::labels::{file_safe, scene_name, ConfigLabels};
use crate::pareto;

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let rows: Vec<&Rec> = runs
        .study(StudyKind::Views)
        .into_iter()
        .filter(|r| r.ok() && !r.is_floor())
        .collect();
    let styles = Styles::new(rows.iter().copied());
    let mut figs = Vec::new();
    for (key, g) in Runs::group_by(rows.iter().copied(), |r| {
        format!("{}\u{0}{}", r.get(cols::SCENE_LABEL), resolution(r))
    }) {
        let (label, res) = key.split_once('\u{0}').unwrap_or((&key, ""));
        let path = g[0].get(cols::CAMERA_PATH).to_string();
        // The label names the path and its keys.
        let name = format!("{}, {res}", scene_name(label));
        let stem = file_safe(&format!("views_{label}_{res}"));
        let labels = ConfigLabels::new(g.iter().copied());
        figs.push(flicker_vs_time(&g, &labels, &styles, &name, &stem, dir)?);
        let flip = g.iter().any(|r| r.f(cols::FLIP_MEAN).is_some());
        let (err_key, err_label) = if flip {
            ("flip", "FLIP mean of the view vs its truth")
        } else {
            ("rmse", "RMSE of the view vs its truth")
        };
        figs.push(along_path(
            &g,
            &labels,
            &styles,
            err_key,
            &format!("Error along the path — {name}"),
            err_label,
            &format!("{stem}_error"),
            "Each view judged against its own exact truth. Zero is drawn in the band under the log axis.",
            dir,
        )?);
        let key = if path == "at_rest" {
            "changed"
        } else {
            "popping"
        };
        let (title, y_label, caption) = if path == "at_rest" {
            (
                format!("Changed pixels at rest — {name}"),
                "share of pixels that differ from the previous frame",
                "The same view repeated: a method without timing-dependent hazards changes no pixel (0, in the band under the log axis).".to_string(),
            )
        } else {
            (
                format!("Popping along the path — {name}"),
                "share of pixels whose error jumps by > ε",
                format!(
                    "The step arriving at each view (none at view 0). ε = pop_epsilon = {}. An exact method never pops (0, in the band under the log axis).",
                    g[0].get(cols::POP_EPSILON)
                ),
            )
        };
        figs.push(along_path(
            &g,
            &labels,
            &styles,
            key,
            &title,
            y_label,
            &format!("{stem}_{key}"),
            &caption,
            dir,
        )?);
    }
    Ok(figs)
}

/// Flicker (mean over steps) against the median GPU time over the path, whiskered to the p99.
fn flicker_vs_time(
    g: &[&Rec],
    labels: &ConfigLabels,
    styles: &Styles,
    name: &str,
    stem: &str,
    dir: &Path,
) -> Result<Figure> {
    let xy = |r: &Rec| Some((r.f(cols::GPU_MS_MEDIAN)?, r.f(cols::FLICKER_MEAN)?));
    let pts: Vec<(f64, f64)> = g
        .iter()
        .map(|r| xy(r).unwrap_or((f64::NAN, f64::NAN)))
        .collect();
    let front: Vec<Named> = pareto::front(&pts)
        .into_iter()
        .map(|i| Named {
            x: pts[i].0,
            y: pts[i].1,
            text: labels.get(g[i]),
        })
        .collect();
    let series = config_series(g, labels, styles, |r| {
        let (x, y) = xy(r)?;
        let mut p = Pt::new(x, y).flagged(r.flagged());
        p.xhi = r.f(cols::GPU_MS_PATH_P99);
        p.xlo = p.xhi.map(|_| x);
        Some(p)
    });
    let chart = XY {
        title: format!("Flicker vs time over the path — {name}"),
        x_label: "GPU ms per frame (median over the views; whisker to the p99)".into(),
        y_label: "flicker: unexplained frame-to-frame change".into(),
        log_x: true,
        log_y: true,
        lines: false,
        series,
        front,
        front_name: "Pareto front (flicker, time)".into(),
        zero_label: "no flicker (0)".into(),
        ..Default::default()
    };
    chart.draw(
        dir,
        &format!("{stem}_flicker"),
        &format!(
            "Flicker = mean over consecutive views of the mean over pixels of |(I_t − I_t−1) − (T_t − T_t−1)|: the part of the method's change the truth's does not explain. \
             An exact method stays within its f32 bound (flicker_bound_mean). Hollow: flagged. {}",
            labels.fixed_note()
        ),
    )
}

/// One line per configuration: the `key` array of its `path_series` against the view index.
#[allow(
    clippy::too_many_arguments,
    reason = "one chart: its rows, labels, styles, series key, texts and output"
)]
fn along_path(
    g: &[&Rec],
    labels: &ConfigLabels,
    styles: &Styles,
    key: &str,
    title: &str,
    y_label: &str,
    stem: &str,
    caption: &str,
    dir: &Path,
) -> Result<Figure> {
    let mut series: Vec<Series> = Vec::new();
    for r in g {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(r.get(cols::PATH_SERIES)) else {
            continue;
        };
        let Some(values) = v[key].as_array() else {
            continue;
        };
        let points: Vec<Pt> = values
            .iter()
            .enumerate()
            .filter_map(|(i, x)| Some(Pt::new(i as f64, x.as_f64()?)))
            .collect();
        if points.is_empty() {
            continue;
        }
        let one = Series {
            name: labels.get(r),
            family: styles.family(r),
            color: Some(styles.color(r)),
            points,
        };
        series.push(one);
    }
    let chart = XY {
        title: title.into(),
        x_label: "view along the path".into(),
        y_label: y_label.into(),
        log_y: true,
        lines: true,
        series,
        zero_label: "0".into(),
        ..Default::default()
    };
    chart.draw(dir, stem, &format!("{caption} {}", labels.fixed_note()))
}
