//! Figures of the `prepass` study (issue 10): light pre-pass vs full deferred (time and error vs
//! light count, render-target bytes per pixel), and the CPU-lit light buffer (frame time vs
//! threads with and without the overlapping second view, against the GPU-only frame with the
//! same second view; the GPU-clock gap between pre-pass and material pass and what filled it).

use schema::StudyKind;
use schema::{cols, Col};
use std::path::Path;

use anyhow::Result;

use super::deferred::{rows_by_resolution, safe, series};
use crate::charts::{Bars, Figure, Pt, Series, XY};
use mfx_analysis::data::{Rec, Runs};

const AXES: &[Col] = &[cols::LIGHT_ACCUM, cols::LIGHT_BUFFER_FORMAT];

/// "deferred" or "prepass <light buffer format>".
fn short(r: &Rec) -> String {
    format!(
        "{} {}",
        r.get(cols::METHOD),
        r.get(cols::LIGHT_BUFFER_FORMAT)
    )
    .trim()
    .to_string()
}

fn single_view(r: &Rec) -> bool {
    r.get(cols::SECOND_VIEW) != "true"
}

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let mut figs = Vec::new();
    for (res, at) in rows_by_resolution(runs, StudyKind::Prepass) {
        let stem = safe(&res);
        let one: Vec<&Rec> = at
            .iter()
            .copied()
            .filter(|r| single_view(r) && r.get(cols::METHOD) != "prepass_cpu")
            .collect();
        // Time vs light count.
        let s = series(
            &one,
            |r| r.config_label(AXES),
            |r| Some((r.f(cols::LIGHT_COUNT)?, r.trusted_ms()?)),
        );
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("Light pre-pass vs full deferred: GPU time vs lights — {res}"),
                    x_label: "lights".into(),
                    y_label: "GPU ms per frame (all passes)".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("prepass_time_vs_lights_{stem}"), "deferred: G-buffer + shading (one geometry pass). prepass: depth+normal pre-pass, light buffer, second geometry pass with the materials.")?,
            );
        }
        // Error vs light count, with the packing loss alone (f64) as its own line.
        let mut s = series(
            &one,
            |r| r.config_label(AXES),
            |r| Some((r.f(cols::LIGHT_COUNT)?, r.f(cols::RMSE)?)),
        );
        s.extend(series(
            &one,
            |_| "packing loss alone (f64: diffuse RGB + specular luminance)".into(),
            |r| Some((r.f(cols::LIGHT_COUNT)?, r.f(cols::SPEC_COLOR_LOSS_RMSE)?)),
        ));
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("Error vs the f64 reference — {res}"),
                    zero_label: "exact (0)".into(),
                    x_label: "lights".into(),
                    y_label: "RMSE vs f64 full shading".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("prepass_error_vs_lights_{stem}"), "The light buffer keeps the specular sum's luminance only (A): coloured lights lose the colour of their highlights (dielectrics: grey specular; metals: chroma of the diffuse light). rgba8 stores light ÷ 8 and clamps above 8.")?,
            );
        }
        // Render-target bytes per pixel.
        let cfgs: Vec<String> = {
            let mut v: Vec<String> = Vec::new();
            for r in &one {
                let c = short(r);
                if !v.contains(&c) && r.f(cols::BYTES_RT_WRITTEN).is_some() {
                    v.push(c);
                }
            }
            v
        };
        if !cfgs.is_empty() {
            let px = |r: &Rec| Some(r.f(cols::WIDTH)? * r.f(cols::HEIGHT)?);
            let col = |c: Col| -> Vec<Option<Pt>> {
                cfgs.iter()
                    .map(|cfg| {
                        one.iter()
                            .find(|r| &short(r) == cfg)
                            .and_then(|r| Some(Pt::new(0.0, r.f(c)? / px(r)?)))
                    })
                    .collect()
            };
            let series = vec![
                ("written".into(), col(cols::BYTES_RT_WRITTEN)),
                ("read".into(), col(cols::BYTES_RT_READ)),
            ];
            figs.push(
                Bars {
                    title: format!("Render-target bytes per pixel — {res}"),
                    y_label: "bytes per pixel per frame".into(),
                    log_y: false,
                    categories: cfgs,
                    series,
                    reference: None,
                }
                .draw(dir, &format!("prepass_rt_bytes_{stem}"), "One touch per pixel per target (overdraw not counted); deferred writes the full G-buffer (depth, normal, albedo, specular, material id) and the HDR image.")?,
            );
        }
        // CPU lighting: frame time vs threads, overlap on/off, vs the GPU-only frame.
        let cpu: Vec<&Rec> = at
            .iter()
            .copied()
            .filter(|r| r.get(cols::METHOD) == "prepass_cpu")
            .collect();
        let mut s = series(
            &cpu,
            |r| {
                format!(
                    "CPU-lit, overlap={}, {} lights, {}",
                    r.get(cols::OVERLAP),
                    r.get(cols::LIGHT_COUNT),
                    r.get(cols::LIGHT_BUFFER_FORMAT)
                )
            },
            |r| Some((r.f(cols::THREAD_COUNT)?, r.f(cols::FRAME_MS)?)),
        );
        let tmin = cpu
            .iter()
            .filter_map(|r| r.f(cols::THREAD_COUNT))
            .fold(f64::INFINITY, f64::min);
        let tmax = cpu
            .iter()
            .filter_map(|r| r.f(cols::THREAD_COUNT))
            .fold(0.0, f64::max);
        let lit_on_cpu = |r: &Rec| {
            cpu.iter().any(|c| {
                c.get(cols::LIGHT_COUNT) == r.get(cols::LIGHT_COUNT)
                    && c.get(cols::LIGHT_BUFFER_FORMAT) == r.get(cols::LIGHT_BUFFER_FORMAT)
            })
        };
        for r in at.iter().filter(|r| {
            r.get(cols::METHOD) == "prepass"
                && r.get(cols::SECOND_VIEW) == "true"
                && r.get(cols::LIGHT_ACCUM) == "tiled"
                && lit_on_cpu(r)
                && tmax > tmin
        }) {
            if let Some(f) = r.f(cols::FRAME_MS) {
                let name = format!(
                    "GPU-lit ({}), {} lights, {}",
                    r.get(cols::LIGHT_ACCUM),
                    r.get(cols::LIGHT_COUNT),
                    r.get(cols::LIGHT_BUFFER_FORMAT)
                );
                if !s.iter().any(|x| x.name == name) {
                    s.push(Series::new(name, vec![Pt::new(tmin, f), Pt::new(tmax, f)]));
                }
            }
        }
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("CPU-lit light buffer: frame time vs threads — {res}"),
                    x_label: "CPU worker threads".into(),
                    y_label: "wall ms per frame (both views)".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("prepass_cpu_frame_{stem}"), "Every frame renders the main view and an independent second view. overlap=true submits the second view before the CPU lights, so the GPU renders it meanwhile; GPU-lit lines are the same two views with the light buffer lit on the GPU (flat: no threads).")?,
            );
        }
        // The gap on the GPU clock and how much of it the second view filled.
        let mut s = series(
            &cpu,
            |r| {
                format!(
                    "gap, overlap={}, {} lights",
                    r.get(cols::OVERLAP),
                    r.get(cols::LIGHT_COUNT)
                )
            },
            |r| Some((r.f(cols::THREAD_COUNT)?, r.f(cols::GPU_GAP_MS)?)),
        );
        s.extend(series(
            &cpu,
            |r| {
                format!(
                    "GPU busy in gap, overlap={}, {} lights",
                    r.get(cols::OVERLAP),
                    r.get(cols::LIGHT_COUNT)
                )
            },
            |r| Some((r.f(cols::THREAD_COUNT)?, r.f(cols::GPU_BUSY_IN_GAP_MS)?)),
        ));
        s.extend(series(
            &cpu,
            |r| {
                format!(
                    "CPU lighting, overlap={}, {} lights",
                    r.get(cols::OVERLAP),
                    r.get(cols::LIGHT_COUNT)
                )
            },
            |r| Some((r.f(cols::THREAD_COUNT)?, r.f(cols::CPU_LIGHT_MS)?)),
        ));
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("CPU round trip on the GPU clock — {res}"),
                    x_label: "CPU worker threads".into(),
                    y_label: "ms".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("prepass_cpu_gap_{stem}"), "gap: GPU clock from the end of the pre-pass to the start of the material pass (copy, map, CPU lighting, upload). busy: timed GPU passes inside it (the second view when overlapped; none: drawn in the 0 band under the axis). A software rasteriser (lavapipe) shares the CPU cores, so there it cannot overlap for free.")?,
            );
        }
    }
    Ok(figs)
}
