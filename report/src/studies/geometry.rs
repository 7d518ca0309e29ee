//! Figures of the `geometry` study (Bavoil 2007, ch. 3, on today's GPUs): throughput vs vertices
//! per draw (Fig. 3.1), time vs number of batches (Fig. 3.2), interleaved vs separate buffers by
//! attribute count (Fig. 3.3), bar charts for index precision × mesh order × strips (Tables
//! 3.2–3.3) with measured vs predicted vertex-shader runs per triangle, vertex formats (Table
//! 3.4), and the raster-stage check. Each `[[study]]` of a suite is told apart by the axes it
//! sweeps (the point key's last field); every figure has min–max whiskers where times are drawn.

use schema::StudyKind;
use schema::{cols, Col, PointKey};
use std::path::Path;

use anyhow::Result;

use crate::charts::{Bars, Figure, Pt, Series, XY};
use crate::labels::{file_safe, scene_name};
use mfx_analysis::data::{resolution, Rec, Runs};

/// What the whiskers of this study's charts show.
const WHISKERS: &str = "Whiskers: 95 % CI of the median GPU time where the CSV has one (none otherwise: min–max is not a spread of the median).";

/// The axes a row's `[[study]]` swept (from its point key).
fn swept(r: &Rec) -> Vec<String> {
    r.get(cols::POINT_KEY)
        .parse::<PointKey>()
        .map(|k| k.axis_names().into_iter().map(String::from).collect())
        .unwrap_or_default()
}

fn sweeps(r: &Rec, axis: Col) -> bool {
    swept(r).iter().any(|a| a == axis.name)
}

/// Triangles drawn per frame: `draw_triangles` (a prefix) or the whole scene.
fn drawn(r: &Rec) -> Option<f64> {
    match r.f(cols::DRAW_TRIANGLES) {
        Some(d) if d > 0.0 => Some(d),
        _ => r.f(cols::TRIANGLES),
    }
}

/// Vertices per draw call in the thesis's sense: indices (indexed) or corners (non-indexed).
fn vertices_per_draw(r: &Rec) -> Option<f64> {
    let batches = r.f(cols::BATCHES)?.max(1.0);
    let v = if r.get(cols::INDEXED) == "false" {
        3.0 * drawn(r)?
    } else {
        r.f(cols::INDEX_COUNT)?
    };
    Some(v / batches)
}

/// A rate `amount / gpu time`, whiskers from the CI of the median time when measured.
fn rate(r: &Rec, x: f64, amount: f64, scale: f64) -> Option<Pt> {
    let ms = r.trusted_ms()?;
    if ms <= 0.0 {
        return None;
    }
    let per = |m: f64| (m > 0.0).then(|| amount / (m * 1e-3) / scale);
    let (lo, hi) = match r.gpu_ci() {
        Some((lo, hi)) => (per(hi), per(lo)),
        None => (None, None),
    };
    Some(Pt::spread(x, amount / (ms * 1e-3) / scale, lo, hi).flagged(r.flagged()))
}

fn gpu_ms(r: &Rec, x: f64) -> Option<Pt> {
    crate::points::time_pt(r, x)
}

fn push(series: &mut Vec<Series>, name: String, p: Pt) {
    match series.iter_mut().find(|s| s.name == name) {
        Some(s) => s.points.push(p),
        None => series.push(Series::new(name, vec![p])),
    }
}

fn sorted(mut series: Vec<Series>) -> Vec<Series> {
    for s in &mut series {
        s.points.sort_by(|a, b| a.x.total_cmp(&b.x));
    }
    series
}

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let rows: Vec<&Rec> = runs
        .study(StudyKind::Geometry)
        .into_iter()
        .filter(|r| r.ok() && r.get(cols::METHOD) == "geometry")
        .collect();
    let mut figs = Vec::new();
    for (res, at) in Runs::group_by(rows.iter().copied(), resolution) {
        throughput(&at, &res, dir, &mut figs)?;
        batching(&at, &res, dir, &mut figs)?;
        layout(&at, &res, dir, &mut figs)?;
        index_precision(&at, &res, dir, &mut figs)?;
        formats(&at, &res, dir, &mut figs)?;
        raster_check(&at, &res, dir, &mut figs)?;
    }
    Ok(figs)
}

/// Fig. 3.1: triangles/s vs vertices per draw call (log x), indexed and non-indexed, per scene.
fn throughput(at: &[&Rec], res: &str, dir: &Path, figs: &mut Vec<Figure>) -> Result<()> {
    let mut series = Vec::new();
    for r in at.iter().filter(|r| sweeps(r, cols::DRAW_TRIANGLES)) {
        let (Some(x), Some(t)) = (vertices_per_draw(r), drawn(r)) else {
            continue;
        };
        let name = format!(
            "{} — {}",
            scene_name(r.get(cols::SCENE_LABEL)),
            if r.get(cols::INDEXED) == "false" {
                "non-indexed"
            } else {
                "indexed"
            }
        );
        if let Some(p) = rate(r, x, t, 1e6) {
            push(&mut series, name, p);
        }
    }
    if series.iter().map(|s| s.points.len()).sum::<usize>() < 2 {
        return Ok(());
    }
    let xy = XY {
        title: format!("Geometry throughput vs vertices per draw call — {res}"),
        x_label: "vertices per draw call (indices, or corners when non-indexed)".into(),
        y_label: "million triangles per second (GPU time)".into(),
        log_x: true,
        log_y: false,
        lines: true,
        series: sorted(series),
        ..Default::default()
    };
    figs.push(xy.draw(
        dir,
        &format!("geometry_throughput_vs_vertices_{res}"),
        &format!("Thesis Fig. 3.1: one draw of a growing prefix of the mesh; the thesis saw a cliff above ~1M vertices per indexed draw on GeForce 7 and none without indices. {WHISKERS}"),
    )?);
    Ok(())
}

/// Fig. 3.2: time per frame vs number of draw calls at a fixed total, GPU and wall clock.
fn batching(at: &[&Rec], res: &str, dir: &Path, figs: &mut Vec<Figure>) -> Result<()> {
    let mut series = Vec::new();
    for r in at
        .iter()
        .filter(|r| sweeps(r, cols::BATCH_SIZE) && !sweeps(r, cols::INDEX_FORMAT))
    {
        let Some(b) = r.f(cols::BATCHES) else {
            continue;
        };
        let label = r.get(cols::SCENE_LABEL);
        if let Some(p) = gpu_ms(r, b) {
            push(&mut series, format!("{} — GPU", scene_name(label)), p);
        }
        if let Some(c) = r.f(cols::CPU_MS_MEDIAN) {
            push(
                &mut series,
                format!("{} — wall clock", scene_name(label)),
                Pt::new(b, c),
            );
        }
    }
    if series.iter().map(|s| s.points.len()).sum::<usize>() < 2 {
        return Ok(());
    }
    let xy = XY {
        title: format!("Time per frame vs number of batches — {res}"),
        x_label: "draw calls per frame (same triangles in total)".into(),
        y_label: "time per frame [ms]".into(),
        log_x: true,
        log_y: true,
        lines: true,
        series: sorted(series),
        ..Default::default()
    };
    figs.push(xy.draw(
        dir,
        &format!("geometry_time_vs_batches_{res}"),
        &format!("Thesis Fig. 3.2: the mesh cut into 1 … N draw calls. GPU = timestamped render pass; wall clock = encode + submit + wait, where per-draw CPU cost shows. {WHISKERS}"),
    )?);
    Ok(())
}

/// Fig. 3.3: interleaved vs separate vertex buffers as extra float32x4 attributes grow.
fn layout(at: &[&Rec], res: &str, dir: &Path, figs: &mut Vec<Figure>) -> Result<()> {
    let mut series = Vec::new();
    for r in at.iter().filter(|r| sweeps(r, cols::EXTRA_ATTRIBUTES)) {
        let Some(x) = r.f(cols::EXTRA_ATTRIBUTES) else {
            continue;
        };
        if let Some(p) = gpu_ms(r, x) {
            push(
                &mut series,
                format!(
                    "{} — {}",
                    scene_name(r.get(cols::SCENE_LABEL)),
                    r.get(cols::LAYOUT)
                ),
                p,
            );
        }
    }
    if series.iter().map(|s| s.points.len()).sum::<usize>() < 2 {
        return Ok(());
    }
    let xy = XY {
        title: format!("Interleaved vs separate vertex buffers — {res}"),
        x_label: "extra float32x4 attributes per vertex".into(),
        y_label: "GPU time per frame [ms]".into(),
        log_x: false,
        log_y: false,
        lines: true,
        series: sorted(series),
        ..Default::default()
    };
    figs.push(xy.draw(
        dir,
        &format!("geometry_layout_vs_attributes_{res}"),
        &format!("Thesis Fig. 3.3: one draw of the whole mesh, every attribute read by the vertex shader. {WHISKERS}"),
    )?);
    Ok(())
}

/// Tables 3.2–3.3: index precision × mesh order × primitive, triangles/s per scene, and the
/// measured vertex-shader runs per triangle beside meshopt's prediction (ACMR).
fn index_precision(at: &[&Rec], res: &str, dir: &Path, figs: &mut Vec<Figure>) -> Result<()> {
    let rows: Vec<&Rec> = at
        .iter()
        .copied()
        .filter(|r| sweeps(r, cols::INDEX_FORMAT))
        .collect();
    for label in Runs::distinct(rows.iter().copied(), cols::SCENE_LABEL) {
        let g: Vec<&Rec> = rows
            .iter()
            .copied()
            .filter(|r| r.get(cols::SCENE_LABEL) == label)
            .collect();
        let cat = |r: &Rec| format!("{} {}", r.get(cols::MESH_ORDER), r.get(cols::PRIMITIVE));
        let categories = Runs::distinct_by(&g, cat);
        let find =
            |c: &str, f: &dyn Fn(&Rec) -> bool| g.iter().copied().find(|r| cat(r) == c && f(r));
        let series: Vec<(String, Vec<Option<Pt>>)> = ["uint16", "uint32"]
            .iter()
            .map(|fmt| {
                let vals = categories
                    .iter()
                    .map(|c| {
                        find(c, &|r: &Rec| r.get(cols::INDEX_FORMAT) == *fmt)
                            .and_then(|r| rate(r, 0.0, drawn(r)?, 1e6))
                    })
                    .collect();
                (fmt.to_string(), vals)
            })
            .filter(|(_, v): &(String, Vec<Option<Pt>>)| v.iter().any(|p| p.is_some()))
            .collect();
        if !series.is_empty() {
            figs.push(
                Bars {
                    title: format!("Index precision × mesh order — {}, {res}", scene_name(&label)),
                    y_label: "million triangles per second".into(),
                    log_y: false,
                    categories: categories.clone(),
                    series,
                    reference: None,
                }
                .draw(
                    dir,
                    &format!("geometry_index_precision_{}_{res}", file_safe(&label)),
                    &format!("Thesis Tables 3.2–3.3: 16- vs 32-bit indices for each triangle order (original, shuffled, meshopt vertex cache, cache + fetch) as lists and as strips with primitive restart. {WHISKERS}"),
                )?,
            );
        }
        // Measured vs predicted post-transform cache behaviour (32-bit: no batch cuts).
        let mut series: Vec<(String, Vec<Option<Pt>>)> = Vec::new();
        for (name, col) in [
            ("meshopt ACMR (FIFO 16)", cols::ACMR),
            ("measured VS runs / triangle", cols::VS_ACMR),
        ] {
            let vals = categories
                .iter()
                .map(|c| {
                    find(c, &|r: &Rec| r.get(cols::INDEX_FORMAT) == "uint32")
                        .and_then(|r| r.f(col))
                        .map(|v| Pt::new(0.0, v))
                })
                .collect::<Vec<_>>();
            if vals.iter().any(|v| v.is_some()) {
                series.push((name.to_string(), vals));
            }
        }
        if !series.is_empty() {
            figs.push(
                Bars {
                    title: format!("Vertex-shader runs per triangle — {}, {res}", scene_name(&label)),
                    y_label: "vertex-shader invocations per triangle".into(),
                    log_y: false,
                    categories,
                    series,
                    reference: Some(0.5),
                }
                .draw(
                    dir,
                    &format!("geometry_acmr_{}_{res}", file_safe(&label)),
                    "Measured (pipeline statistics) against meshopt's FIFO-16 simulation of the same index stream, 32-bit indices; 3 = no reuse, the line at 0.5 is the ideal of a closed mesh.",
                )?,
            );
        }
    }
    Ok(())
}

/// Table 3.4: one bar per attribute format, GPU time, per scene.
fn formats(at: &[&Rec], res: &str, dir: &Path, figs: &mut Vec<Figure>) -> Result<()> {
    const AXES: [(Col, &str); 4] = [
        (cols::VERTEX_FORMAT, "position"),
        (cols::NORMAL_FORMAT, "normal"),
        (cols::COLOR_FORMAT, "colour"),
        (cols::TEXCOORD_FORMAT, "texcoord"),
    ];
    let rows: Vec<&Rec> = at
        .iter()
        .copied()
        .filter(|r| {
            !sweeps(r, cols::INDEX_FORMAT)
                && !sweeps(r, cols::EXTRA_ATTRIBUTES)
                && AXES.iter().any(|(a, _)| sweeps(r, *a))
        })
        .collect();
    // One chart per scene and per [[study]] (the set of format axes it swept).
    let which = |r: &Rec| {
        let s = swept(r);
        AXES.iter()
            .filter(|(a, _)| s.iter().any(|x| x == a.name))
            .map(|(_, n)| *n)
            .collect::<Vec<_>>()
            .join(" × ")
    };
    for label in Runs::distinct(rows.iter().copied(), cols::SCENE_LABEL) {
        let of_scene: Vec<&Rec> = rows
            .iter()
            .copied()
            .filter(|r| r.get(cols::SCENE_LABEL) == label)
            .collect();
        for study in Runs::distinct_by(&of_scene, which) {
            let g: Vec<&Rec> = of_scene
                .iter()
                .copied()
                .filter(|r| which(r) == study)
                .collect();
            // A category names the formats that vary in this study, e.g. "normal snorm8x4";
            // swept axes with one value (e.g. normal none) go in the title.
            let varying: Vec<(Col, &str)> = AXES
                .iter()
                .copied()
                .filter(|(a, _)| Runs::distinct(g.iter().copied(), *a).len() > 1)
                .collect();
            let fixed: Vec<String> = AXES
                .iter()
                .filter(|(a, _)| sweeps(g[0], *a) && !varying.iter().any(|(v, _)| v == a))
                .map(|(a, n)| format!("{n} {}", g[0].get(*a)))
                .collect();
            let cat = |r: &Rec| {
                varying
                    .iter()
                    .map(|(a, n)| format!("{n} {}", r.get(*a)))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let categories = Runs::distinct_by(&g, cat);
            let vals = categories
                .iter()
                .map(|c| {
                    g.iter()
                        .copied()
                        .find(|r| cat(r) == *c)
                        .and_then(|r| gpu_ms(r, 0.0))
                })
                .collect();
            figs.push(
                Bars {
                    title: format!(
                        "Vertex formats ({}{}) — {}, {res}",
                        varying.iter().map(|(_, n)| *n).collect::<Vec<_>>().join(" × "),
                        if fixed.is_empty() {
                            String::new()
                        } else {
                            format!("; {}", fixed.join(", "))
                        },
                        scene_name(&label)
                    ),
                    y_label: "GPU time per frame [ms]".into(),
                    log_y: false,
                    categories,
                    series: vec![("GPU ms".into(), vals)],
                    reference: None,
                }
                .draw(
                    dir,
                    &format!(
                        "geometry_formats_{}_{}_{res}",
                        file_safe(&study),
                        file_safe(&label)
                    ),
                    &format!("Thesis Table 3.4: one draw of the whole mesh per attribute format; attributes not swept keep their defaults (position float32x3, normal float32x3, no colour, no texcoord). {WHISKERS}"),
                )?,
            );
        }
    }
    Ok(())
}

/// The thesis's check: time at the suite's viewport over time at a small one (≈ 1 when the
/// raster stage is not the bottleneck), against the GPU time of the point.
fn raster_check(at: &[&Rec], res: &str, dir: &Path, figs: &mut Vec<Figure>) -> Result<()> {
    let mut series = Vec::new();
    for r in at {
        if let (Some(ms), Some(ratio)) = (r.trusted_ms(), r.f(cols::RASTER_BOUND_RATIO)) {
            push(
                &mut series,
                scene_name(r.get(cols::SCENE_LABEL)),
                Pt::new(ms, ratio).flagged(r.flagged()),
            );
        }
    }
    if series.is_empty() {
        return Ok(());
    }
    let xy = XY {
        title: format!("Raster-stage check — {res}"),
        x_label: "GPU time per frame at the suite's viewport [ms]".into(),
        y_label: "time at the viewport / time at the small viewport".into(),
        log_x: true,
        log_y: false,
        lines: false,
        series: sorted(series),
        ..Default::default()
    };
    figs.push(xy.draw(
        dir,
        &format!("geometry_raster_check_{res}"),
        "One point per measured row; ≈ 1 means shrinking the viewport does not change the time, so the raster stage is not the bottleneck (the thesis's method).",
    )?);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(pairs: &[(Col, &str)]) -> Rec {
        Rec(pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect())
    }

    #[test]
    fn swept_axes_come_from_the_point_key() {
        let r = rec(&[(
            cols::POINT_KEY,
            "geometry|quads(depth_complexity=8,seed=1)|64x64|geometry|index_format=uint16,mesh_order=vcache",
        )]);
        assert_eq!(
            swept(&r),
            vec![cols::INDEX_FORMAT.name, cols::MESH_ORDER.name]
        );
        assert!(sweeps(&r, cols::MESH_ORDER) && !sweeps(&r, cols::BATCH_SIZE));
    }

    #[test]
    fn vertices_per_draw_counts_indices_or_corners() {
        let idx = rec(&[
            (cols::INDEXED, "true"),
            (cols::INDEX_COUNT, "3000"),
            (cols::BATCHES, "3"),
            (cols::TRIANGLES, "1000"),
            (cols::DRAW_TRIANGLES, "0"),
        ]);
        assert_eq!(vertices_per_draw(&idx), Some(1000.0));
        let non = rec(&[
            (cols::INDEXED, "false"),
            (cols::BATCHES, "1"),
            (cols::TRIANGLES, "1000"),
            (cols::DRAW_TRIANGLES, "100"),
        ]);
        assert_eq!(vertices_per_draw(&non), Some(300.0));
    }
}
