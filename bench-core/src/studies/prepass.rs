//! The `prepass` study (issue 10): the light pre-pass renderer (`shading::prepass`) against
//! full deferred shading on the same scene — time, render-target bytes, error vs the same f64
//! reference as the `deferred` study, and the specular colour the RGB+A packing loses — and the
//! light buffer computed on CPU cores while the GPU renders an independent view.
//!
//! Methods: `deferred` (axis `light_accum` = naive | tiled), `prepass` (`light_accum`,
//! `light_buffer_format`, `second_view`), `prepass_cpu` (`light_buffer_format`,
//! `thread_count`, `overlap`; always with the independent view). Compare `prepass_cpu` with
//! `prepass(second_view=true)`: the same two views, lit on the GPU.

use std::collections::BTreeMap;
use std::time::Instant;

use scenarios::suite::axis_product;
use scenarios::{Params, StudySpec};

use super::deferred::{gbuffer_of, rel_err_max};
use super::{Emit, GroupCtx, PointSpec, Study};
use crate::methods::{bool_param, int_param, str_param, Prepared};
use crate::metrics::{image_error, BAD_PIXEL_TOL};
use crate::record::{Column, Row};
use crate::runner::{failed_row, set_params, skipped_row};
use crate::shading::gbuffer::FULL_BYTES_PER_PIXEL;
use crate::shading::gpu_paths::{Deferred, Path};
use crate::shading::prepass::{self, Accum, LbFormat, PrePass};
use crate::shading::{reference, ShadeSetup};
use crate::timing::{GpuTimer, Stats};
use crate::{CoreError, Result};

/// CSV columns this study owns (documented in results/README.md).
pub const COLUMNS: &[Column] = &[
    Column { name: "light_accum", doc: "how the lighting is accumulated: naive (every light, fullscreen) | tiled (GPU tile culling) | cpu (CPU tiles)" },
    Column { name: "light_buffer_format", doc: "light pre-pass light buffer: rgba8 (light ÷ 8, clamped) | rgba16f | rg11b10 (+ r16f for the specular term)" },
    Column { name: "second_view", doc: "true: an independent second-camera view (full deferred, tiled) is rendered in the same frame" },
    Column { name: "overlap", doc: "CPU lighting: true = the second view is submitted before the CPU lights, so the GPU renders it meanwhile; false = after" },
    Column { name: "bytes_rt_written", doc: "render-target bytes written per frame by the main view, one touch per pixel (overdraw not counted)" },
    Column { name: "bytes_rt_read", doc: "render-target bytes read per frame by the main view, one touch per pixel (overdraw not counted)" },
    Column { name: "spec_color_loss_rmse", doc: "RMSE of the f64 light pre-pass image (diffuse RGB + specular luminance packing) vs the f64 full reference: colour lost by the packing alone" },
    Column { name: "format_rmse", doc: "RMSE vs the f64 light pre-pass image: what the light-buffer format and f32 arithmetic add" },
    Column { name: "frame_ms", doc: "median wall-clock ms per frame, first submit to all GPU work done (both views when second_view)" },
    Column { name: "gpu_idle_ms", doc: "median frame_ms minus the frame's summed GPU pass times: time the GPU had no timed work" },
    Column { name: "latency_ms", doc: "median ms from submitting the pre-pass to the main view's final image being complete" },
    Column { name: "gpu_gap_ms", doc: "median GPU-clock ms from the end of the pre-pass to the start of the material pass: the lights pass, or (CPU lighting) copy + map + CPU lighting + upload" },
    Column { name: "gpu_busy_in_gap_ms", doc: "median timed GPU pass ms inside gpu_gap_ms: the lights pass, or (CPU lighting) the independent view that ran while the CPU lit — the measured overlap" },
    Column { name: "map_wait_ms", doc: "CPU lighting: median ms from submitting the pre-pass to the depth/normal read-back being mapped (blocking wait)" },
];

const METHODS: &[&str] = &["deferred", "prepass", "prepass_cpu"];

fn axes_of(m: &str) -> &'static [&'static str] {
    match m {
        "deferred" => &["light_accum"],
        "prepass" => &["light_accum", "light_buffer_format", "second_view"],
        _ => &["light_buffer_format", "thread_count", "overlap"],
    }
}

pub struct PrepassStudy;

struct Timed {
    gpu: Option<Stats>,
    wall: Stats,
    idle: Stats,
    pass: BTreeMap<String, f64>,
    /// (gap, busy in gap) medians on the GPU clock, where the frame has both passes.
    gap: Option<(f64, f64)>,
}

/// GPU clock from the end of the pre-pass to the start of the material pass, and the timed
/// pass time inside that interval (the lights pass, or the independent view's passes).
fn gap_of(spans: &[(String, f64, f64)]) -> Option<(f64, f64)> {
    let a = spans.iter().find(|s| s.0 == "prepass")?.2;
    let b = spans.iter().find(|s| s.0 == "material")?.1;
    let busy = spans
        .iter()
        .filter(|s| s.0 != "prepass" && s.0 != "material")
        .map(|s| (s.2.min(b) - s.1.max(a)).max(0.0))
        .sum();
    Some(((b - a).max(0.0), busy))
}

/// Warm-up + timed frames of `frame`, each followed by a full GPU wait.
fn time_frames(
    ctx: &GroupCtx<'_>,
    mut frame: impl FnMut(&mut GpuTimer) -> Result<()>,
) -> Result<Timed> {
    let gpu = ctx.gpu;
    let mut timer = GpuTimer::new(gpu);
    let (mut g, mut w, mut idle) = (vec![], vec![], vec![]);
    let (mut gap, mut busy) = (vec![], vec![]);
    let mut per: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for rep in 0..ctx.warmup + ctx.reps {
        timer.begin_frame();
        let t0 = Instant::now();
        frame(&mut timer)?;
        gpu.wait()?;
        let wall = t0.elapsed().as_secs_f64() * 1e3;
        let spans = timer.read_spans(gpu)?;
        let passes: Vec<(String, f64)> = spans.iter().map(|s| (s.0.clone(), s.2 - s.1)).collect();
        gpu.check_lost()?;
        if rep >= ctx.warmup {
            if let Some((a, b)) = gap_of(&spans) {
                gap.push(a);
                busy.push(b);
            }
            w.push(wall);
            if timer.enabled() {
                let sum: f64 = passes.iter().map(|(_, ms)| ms).sum();
                g.push(sum);
                idle.push((wall - sum).max(0.0));
                for (l, ms) in prepass::sum_passes(&passes) {
                    per.entry(l).or_default().push(ms);
                }
            }
        }
    }
    Ok(Timed {
        gpu: Stats::of(&g),
        wall: Stats::of(&w).unwrap_or_default(),
        idle: Stats::of(&idle).unwrap_or_default(),
        pass: per
            .into_iter()
            .map(|(l, v)| (l, Stats::of(&v).map(|s| s.median).unwrap_or(0.0)))
            .collect(),
        gap: Stats::of(&gap)
            .zip(Stats::of(&busy))
            .map(|(a, b)| (a.median, b.median)),
    })
}

fn set_times(row: &mut Row, t: &Timed) {
    if let Some(g) = t.gpu {
        row.set_f("gpu_ms_median", g.median)
            .set_f("gpu_ms_min", g.min)
            .set_f("gpu_ms_max", g.max)
            .set_f("gpu_ms_rel_noise", g.rel_noise)
            .set_f("gpu_idle_ms", t.idle.median);
    }
    if let Some((gap, busy)) = t.gap {
        row.set_f("gpu_gap_ms", gap)
            .set_f("gpu_busy_in_gap_ms", busy);
    }
    row.set_f("cpu_ms_median", t.wall.median)
        .set_f("cpu_ms_min", t.wall.min)
        .set_f("cpu_ms_max", t.wall.max)
        .set_f("frame_ms", t.wall.median)
        .set(
            "pass_ms",
            serde_json::to_string(&t.pass).unwrap_or_default(),
        );
}

fn median(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.collect();
    Stats::of(&v).map(|s| s.median).unwrap_or(0.0)
}

impl Study for PrepassStudy {
    fn kind(&self) -> &'static str {
        "prepass"
    }
    fn describe(&self) -> &'static str {
        "light pre-pass vs full deferred; light buffer formats; CPU lighting overlapped with a second GPU view"
    }
    fn points(&self, spec: &StudySpec) -> Result<Vec<PointSpec>> {
        let mut out = Vec::new();
        for name in &spec.methods {
            if !METHODS.contains(&name.as_str()) {
                return Err(CoreError::Param(format!(
                    "unknown prepass method '{name}' (known: {})",
                    METHODS.join(", ")
                )));
            }
            for params in axis_product(&spec.axes, axes_of(name)) {
                out.push(PointSpec {
                    method: name.clone(),
                    params,
                });
            }
        }
        Ok(out)
    }

    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
        let (gpu, scene, gscene) = (ctx.gpu, ctx.scene, ctx.gscene);
        let setup = ShadeSetup::new(scene, gscene.width, gscene.height);
        let gb = gbuffer_of(gpu, scene, gscene, false)?;
        let terms = reference::all_terms(&setup, &gb);
        let exact = reference::image_from_terms(&gb, &terms);
        let packed = reference::prepass_image(&gb, &terms);
        let loss = image_error(
            &exact,
            &packed
                .iter()
                .map(|p| p.map(|v| v as f32))
                .collect::<Vec<_>>(),
            BAD_PIXEL_TOL,
        )
        .rmse;
        let px = gscene.pixels() as u64;
        for (i, pt) in ctx.group.points.iter().enumerate() {
            let mut row = Row::new();
            row.set("method", &pt.method)
                .set("light_count", scene.lights.len())
                .set("exact", false);
            set_params(&mut row, &pt.params)?;
            match self.run_point(ctx, &pt.method, &pt.params, &mut row) {
                Ok(Some((img, is_prepass))) => {
                    let e = image_error(&exact, &img, BAD_PIXEL_TOL);
                    row.set_f("rmse", e.rmse)
                        .set_f("psnr_db", e.psnr_db)
                        .set_f("max_abs_err", e.max_abs)
                        .set_f("bad_pixel_frac", e.bad_pixel_frac)
                        .set_f("bad_pixel_tol", BAD_PIXEL_TOL)
                        .set("non_finite", e.non_finite)
                        .set_f("rel_err_max", rel_err_max(&exact, &img));
                    if is_prepass {
                        row.set_f("spec_color_loss_rmse", loss).set_f(
                            "format_rmse",
                            image_error(&packed, &img, BAD_PIXEL_TOL).rmse,
                        );
                    } else {
                        row.set("bytes_rt_written", px * (FULL_BYTES_PER_PIXEL + 16))
                            .set("bytes_rt_read", px * FULL_BYTES_PER_PIXEL);
                    }
                    emit(i, row)?;
                }
                Ok(None) => emit(i, row)?,
                Err(Skip(why)) => emit(i, skipped_row(row, &why))?,
                Err(Fail(why)) => emit(i, failed_row(row, &why))?,
            }
        }
        Ok(())
    }
}

enum PointErr {
    Skip(String),
    Fail(String),
}
use PointErr::{Fail, Skip};

/// Some((image, is_prepass)) when the point made an image.
type PointResult = std::result::Result<Option<(Vec<[f32; 4]>, bool)>, PointErr>;

impl From<CoreError> for PointErr {
    fn from(e: CoreError) -> Self {
        Fail(e.to_string())
    }
}

impl PrepassStudy {
    /// Runs one point: Some((image, is_prepass)) when it made an image.
    fn run_point(
        &self,
        ctx: &GroupCtx<'_>,
        method: &str,
        p: &Params,
        row: &mut Row,
    ) -> PointResult {
        let (gpu, scene, gscene) = (ctx.gpu, ctx.scene, ctx.gscene);
        let accum_name = str_param(p, "light_accum", "tiled", &["naive", "tiled"]).map_err(Skip)?;
        let tiled = accum_name == "tiled";
        if method == "deferred" {
            row.set("light_accum", &accum_name);
            let path = if tiled {
                row.set("tile_size", 16).set("cull_levels", 1);
                Path::Tiled {
                    tile: 16,
                    levels: 1,
                }
            } else {
                Path::Naive
            };
            let mut d = Deferred::new(gpu, scene, gscene, path, 0.0, false)?;
            let t = time_frames(ctx, |timer| d.frame(gpu, gscene, timer).map(|_| ()))?;
            set_times(row, &t);
            row.set("bytes_allocated", d.bytes_allocated())
                .set("geometry_passes", 1);
            return Ok(Some((d.read_image(gpu)?, false)));
        }
        let fmt =
            LbFormat::parse(&str_param(p, "light_buffer_format", "rgba16f", &[]).map_err(Skip)?)
                .map_err(Skip)?;
        row.set("light_buffer_format", fmt.name());
        let (accum, view2) = if method == "prepass_cpu" {
            let threads = int_param(p, "thread_count", 1, 1, 1024).map_err(Skip)? as usize;
            let overlap = bool_param(p, "overlap", true).map_err(Skip)?;
            row.set("light_accum", "cpu").set("second_view", true);
            (Accum::Cpu { threads, overlap }, true)
        } else {
            let v2 = bool_param(p, "second_view", false).map_err(Skip)?;
            row.set("light_accum", &accum_name);
            if tiled {
                row.set("tile_size", 16);
            }
            (
                if tiled {
                    Accum::Tiled { tile: 16 }
                } else {
                    Accum::Naive
                },
                v2,
            )
        };
        prepass::supports(gpu, fmt, accum).map_err(Skip)?;
        let mut pp = PrePass::new(gpu, scene, gscene, fmt, accum, 0.0, view2)?;
        let t = time_frames(ctx, |timer| pp.frame(gpu, gscene, timer))?;
        set_times(row, &t);
        let (wr, rd) = pp.rt_bytes(gscene.pixels() as u64);
        row.set("bytes_rt_written", wr)
            .set("bytes_rt_read", rd)
            .set("bytes_allocated", pp.bytes_allocated())
            .set("geometry_passes", if view2 { 3 } else { 2 });
        let s = &pp.samples[(ctx.warmup as usize).min(pp.samples.len())..];
        if !s.is_empty() {
            row.set_f("latency_ms", median(s.iter().map(|f| f.latency_ms)));
            if matches!(accum, Accum::Cpu { .. }) {
                row.set_f("cpu_light_ms", median(s.iter().map(|f| f.cpu_light_ms)))
                    .set_f("map_wait_ms", median(s.iter().map(|f| f.map_wait_ms)))
                    .set(
                        "notes",
                        format!(
                            "measured: frame_ms = wall clock from the pre-pass submit to both views done; cpu_light_ms = lighting only, decode+light+pack+upload median {:.3} ms; gpu_gap_ms/gpu_busy_in_gap_ms on the GPU clock (busy > 0 = the second view ran while the CPU lit); readiness = map_async callback + blocking poll(Wait) on the pre-pass submission (no spin); one frame in flight, nothing pipelined across frames",
                            median(s.iter().map(|f| f.cpu_total_ms))
                        ),
                    );
            }
        }
        Ok(Some((pp.read_image(gpu)?, true)))
    }
}
