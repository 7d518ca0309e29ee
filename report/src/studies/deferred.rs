//! Figures of the `deferred` study (issue 6): time vs light count per shading path, speedup over
//! naive, error vs time along the attenuation-threshold sweep, and the CPU tile path's scaling
//! over threads. The debug views (tiles coloured by classification id, lights-per-tile heat maps)
//! are PNGs from `mfx shading-views`, not CSV figures.

use schema::StudyKind;
use schema::{cols, Col};
use std::path::Path;

use anyhow::Result;

use crate::charts::{Bars, Figure, Pt, Series, XY};
use mfx_analysis::data::{resolution, Rec, Runs};

/// Axes that tell configurations of one path apart.
pub const CONFIG_AXES: &[Col] = &[
    cols::TILE_SIZE,
    cols::CULL_LEVELS,
    cols::THREAD_COUNT,
    cols::SUN_SHADOW,
    cols::MSAA,
];

pub(crate) fn safe(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .take(60)
        .collect()
}

/// Groups rows into series named by `name`, points sorted by x; a repeated (series, x) keeps
/// its first row (a point measured again by another study of the suite).
pub(crate) fn series(
    rows: &[&Rec],
    name: impl Fn(&Rec) -> String,
    xy: impl Fn(&Rec) -> Option<(f64, f64)>,
) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for r in rows {
        let Some((x, y)) = xy(r) else { continue };
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        let n = name(r);
        match out.iter_mut().find(|s| s.name == n) {
            Some(s) if s.points.iter().any(|p| p.x == x) => {}
            Some(s) => s.points.push(Pt::new(x, y)),
            None => out.push(Series::new(n, vec![Pt::new(x, y)])),
        }
    }
    for s in &mut out {
        s.points.sort_by(|a, b| a.x.total_cmp(&b.x));
    }
    out
}

/// The study's ok rows (floors left out) grouped by resolution, in first-seen order.
pub(crate) fn rows_by_resolution(runs: &Runs, study: StudyKind) -> Vec<(String, Vec<&Rec>)> {
    let rows = runs
        .study(study)
        .into_iter()
        .filter(|r| r.ok() && !r.get(cols::METHOD).starts_with("floor_"));
    Runs::group_by(rows, resolution)
}

/// The time of a row: GPU ms, or the CPU lighting ms of CPU paths.
fn time_ms(r: &Rec) -> Option<f64> {
    if r.get(cols::METHOD) == "cpu_tiled" {
        r.f(cols::CPU_LIGHT_MS)
    } else {
        r.trusted_ms()
    }
}

/// A short configuration label: "tiled 16px L2", "cpu_tiled 64px L1 ×8", "uber shadow8",
/// "classified msaa2".
fn short(r: &Rec) -> String {
    let mut s = r.get(cols::METHOD).to_string();
    if !r.get(cols::TILE_SIZE).is_empty() {
        s += &format!(" {}px", r.get(cols::TILE_SIZE));
    }
    if !r.get(cols::CULL_LEVELS).is_empty() {
        s += &format!(" L{}", r.get(cols::CULL_LEVELS));
    }
    if !r.get(cols::THREAD_COUNT).is_empty() {
        s += &format!(" ×{}", r.get(cols::THREAD_COUNT));
    }
    // Only the shadowed points are marked: the unshadowed ones keep their earlier labels.
    if r.get(cols::SUN_SHADOW) == "taps8" {
        s += " shadow8";
    }
    // Likewise only the multisampled points: "uber msaa2".
    match r.get(cols::MSAA) {
        "x2" => s += " msaa2",
        "x4" => s += " msaa4",
        _ => {}
    }
    s
}

fn no_threshold(r: &Rec) -> bool {
    r.f(cols::ATTENUATION_THRESHOLD).unwrap_or(0.0) == 0.0
}

fn outdoor(r: &Rec) -> bool {
    !r.get(cols::SCENE_LABEL).contains("room=true")
}

pub fn figures(runs: &Runs, dir: &Path) -> Result<Vec<Figure>> {
    let mut figs = Vec::new();
    for (res, at) in rows_by_resolution(runs, StudyKind::Deferred) {
        let stem = safe(&res);
        // Time vs light count per path (no threshold, outdoor city).
        let base: Vec<&Rec> = at
            .iter()
            .copied()
            .filter(|r| no_threshold(r) && outdoor(r))
            .collect();
        let s = series(
            &base,
            |r| r.config_label(CONFIG_AXES),
            |r| Some((r.f(cols::LIGHT_COUNT)?, time_ms(r)?)),
        );
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("Shading time vs light count — {res}"),
                    x_label: "lights".into(),
                    y_label: "time per frame [ms] (GPU; CPU lighting for cpu_tiled)".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("deferred_time_vs_lights_{stem}"), "Shading only (the G-buffer pass is shared). Attenuation threshold 0: culling drops a light only beyond its range, so every path is exact up to f32 rounding.")?,
            );
        }
        // Speedup over naive, per light count.
        let lcs = Runs::distinct(base.iter().copied(), cols::LIGHT_COUNT);
        let cfgs: Vec<String> = Runs::distinct(base.iter().copied(), cols::METHOD)
            .into_iter()
            .filter(|m| m != "naive")
            .flat_map(|m| {
                let mut v: Vec<String> = base
                    .iter()
                    .filter(|r| r.get(cols::METHOD) == m)
                    .map(|r| short(r))
                    .collect();
                v.dedup();
                v
            })
            .fold(Vec::new(), |mut acc, c| {
                if !acc.contains(&c) {
                    acc.push(c);
                }
                acc
            });
        if !cfgs.is_empty() && base.iter().any(|r| r.f(cols::SPEEDUP_VS_NAIVE).is_some()) {
            let series = lcs
                .iter()
                .map(|lc| {
                    (
                        format!("{lc} lights"),
                        cfgs.iter()
                            .map(|c| {
                                base.iter()
                                    .find(|r| r.get(cols::LIGHT_COUNT) == lc && &short(r) == c)
                                    .and_then(|r| r.f(cols::SPEEDUP_VS_NAIVE))
                                    .map(|v| Pt::new(0.0, v))
                            })
                            .collect(),
                    )
                })
                .collect();
            figs.push(
                Bars {
                    title: format!("Speedup over naive — {res}"),
                    y_label: "naive ms / path ms (px: tile, L: culling levels, ×: threads)".into(),
                    log_y: true,
                    categories: cfgs,
                    series,
                    reference: Some(1.0),
                }
                .draw(dir, &format!("deferred_speedup_{stem}"), "Naive = every light at every pixel, fullscreen. Classified vs uber isolates the gain of the Split/Second permutations; tiled at cull_levels=2 is BF3's 64 → 32×16 hierarchy.")?,
            );
        }
        // Error vs time along the threshold sweep.
        let thr: Vec<&Rec> = at
            .iter()
            .copied()
            .filter(|r| !r.get(cols::ATTENUATION_THRESHOLD).is_empty() && outdoor(r))
            .collect();
        let s = series(
            &thr,
            |r| {
                format!(
                    "{} ({} lights)",
                    r.config_label(&[cols::TILE_SIZE, cols::CULL_LEVELS, cols::THREAD_COUNT]),
                    r.get(cols::LIGHT_COUNT)
                )
            },
            |r| Some((time_ms(r)?, r.f(cols::RMSE)?)),
        );
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("Error vs time (attenuation threshold sweep) — {res}"),
                    zero_label: "exact (0)".into(),
                    x_label: "time per frame [ms]".into(),
                    y_label: "RMSE vs f64 reference".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("deferred_error_vs_time_{stem}"), "Each line walks the threshold τ (a light is culled from a tile where I·att ≤ τ everywhere in it); τ = 0 is the leftmost-error end.")?,
            );
        }
        // BF3's culls one at a time (CPU path): time per culling level, quad skip on/off.
        let culls: Vec<&Rec> = at
            .iter()
            .copied()
            .filter(|r| r.get(cols::METHOD) == "cpu_tiled" && no_threshold(r) && outdoor(r))
            .collect();
        let tmax = culls
            .iter()
            .filter_map(|r| r.f(cols::THREAD_COUNT))
            .fold(0.0, f64::max);
        let culls: Vec<&Rec> = culls
            .into_iter()
            .filter(|r| r.f(cols::THREAD_COUNT) == Some(tmax))
            .collect();
        let cats: Vec<String> = Runs::distinct(culls.iter().copied(), cols::CULL_LEVELS)
            .into_iter()
            .map(|l| format!("cull_levels={l}"))
            .collect();
        if culls
            .iter()
            .any(|r| r.get(cols::QUAD_SKIP) == "false" || r.get(cols::SPEC_SKIP) == "false")
        {
            let combos = [
                ("true", "true"),
                ("true", "false"),
                ("false", "true"),
                ("false", "false"),
            ];
            let series = combos
                .iter()
                .flat_map(|(q, sp)| {
                    Runs::distinct(culls.iter().copied(), cols::LIGHT_COUNT)
                        .into_iter()
                        .map(|lc| {
                            let v = cats
                                .iter()
                                .map(|c| {
                                    culls
                                        .iter()
                                        .find(|r| {
                                            format!("cull_levels={}", r.get(cols::CULL_LEVELS))
                                                == *c
                                                && r.get(cols::QUAD_SKIP) == *q
                                                && r.get(cols::SPEC_SKIP) == *sp
                                                && r.get(cols::LIGHT_COUNT) == lc
                                        })
                                        .and_then(|r| Some(Pt::new(0.0, r.f(cols::CPU_LIGHT_MS)?)))
                                })
                                .collect();
                            (format!("quad skip {q}, spec skip {sp}, {lc} lights"), v)
                        })
                        .collect::<Vec<_>>()
                })
                .filter(|(_, v): &(String, Vec<Option<Pt>>)| v.iter().any(|p| p.is_some()))
                .collect();
            figs.push(
                Bars {
                    title: format!("CPU tile path: each cull — {res}, {tmax} threads"),
                    y_label: "CPU lighting ms per frame".into(),
                    log_y: false,
                    categories: cats,
                    series,
                    reference: None,
                }
                .draw(dir, &format!("deferred_cpu_culls_{stem}"), "cull_levels=1: lights culled per 64×64 tile; 2: again per 32×16 sub-tile. Quad skip: a light is skipped for a 4×4 quad when all 16 attenuations are 0; spec skip: a quad without specular colour skips the specular term (both exact: image bit-identical, tested).")?,
            );
        }
        // BF3's normal-cone cull and diffuse-only skip, each on/off, per scene and fraction of
        // diffuse-only lights.
        let bf3: Vec<&Rec> = at
            .iter()
            .copied()
            .filter(|r| r.get(cols::METHOD) == "cpu_tiled" && !r.get(cols::CONE_CULL).is_empty())
            .collect();
        if bf3
            .iter()
            .any(|r| r.get(cols::CONE_CULL) == "false" || r.get(cols::DIFFUSE_SKIP) == "false")
        {
            let key = |r: &Rec| {
                format!(
                    "{}, diffuse-only {}",
                    if outdoor(r) { "city" } else { "room" },
                    r.get(cols::DIFFUSE_ONLY_FRAC)
                )
            };
            let mut cats: Vec<String> = Vec::new();
            for r in &bf3 {
                let k = key(r);
                if !cats.contains(&k) {
                    cats.push(k);
                }
            }
            let series = [
                ("true", "true"),
                ("true", "false"),
                ("false", "true"),
                ("false", "false"),
            ]
            .iter()
            .map(|(cone, dif)| {
                let v = cats
                    .iter()
                    .map(|c| {
                        bf3.iter()
                            .find(|r| {
                                key(r) == *c
                                    && r.get(cols::CONE_CULL) == *cone
                                    && r.get(cols::DIFFUSE_SKIP) == *dif
                            })
                            .and_then(|r| Some(Pt::new(0.0, r.f(cols::CPU_LIGHT_MS)?)))
                    })
                    .collect();
                (format!("cone cull {cone}, diffuse skip {dif}"), v)
            })
            .filter(|(_, v): &(String, Vec<Option<Pt>>)| v.iter().any(|p| p.is_some()))
            .collect();
            figs.push(
                Bars {
                    title: format!("CPU tile path: normal-cone cull and diffuse-only skip — {res}"),
                    y_label: "CPU lighting ms per frame".into(),
                    log_y: false,
                    categories: cats,
                    series,
                    reference: None,
                }
                .draw(dir, &format!("deferred_cpu_bf3_culls_{stem}"), "Cone cull: a light is dropped for a 32×16 sub-tile when no normal in the sub-tile's cone can face it from any point of its position box (exact: image bit-identical, tested). Diffuse skip: lights flagged diffuse-only skip the specular term.")?,
            );
        }
        // CPU scaling over threads.
        let cpu: Vec<&Rec> = at
            .iter()
            .copied()
            .filter(|r| r.get(cols::METHOD) == "cpu_tiled")
            .collect();
        let s = series(
            &cpu,
            |r| {
                format!(
                    "{} lights, cull_levels={}, τ={}, quad skip {}, spec skip {}",
                    r.get(cols::LIGHT_COUNT),
                    r.get(cols::CULL_LEVELS),
                    r.get(cols::ATTENUATION_THRESHOLD),
                    r.get(cols::QUAD_SKIP),
                    r.get(cols::SPEC_SKIP)
                )
            },
            |r| Some((r.f(cols::THREAD_COUNT)?, r.f(cols::CPU_LIGHT_MS)?)),
        );
        if s.iter().any(|s| s.points.len() > 1) {
            figs.push(
                XY {
                    title: format!("CPU tile path (BF3): time vs threads — {res}"),
                    x_label: "worker threads".into(),
                    y_label: "CPU lighting ms per frame".into(),
                    log_x: true,
                    log_y: true,
                    lines: true,
                    series: s,
                    ..Default::default()
                }
                .draw(dir, &format!("deferred_cpu_scaling_{stem}"), "Workers take 64×64 tiles from an atomic counter; SoA 4×4 quads. The G-buffer read-back is not timed.")?,
            );
        }
    }
    Ok(figs)
}
