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

use super::deferred::{gbuffer_of, rel_err_max};
use super::{Emit, GroupCtx, Methods, Study};
use crate::axes::{Axis, Point};
use crate::methods::Prepared;
use crate::metrics::{image_error, BAD_PIXEL_TOL};
use crate::record::cols;
use crate::record::Row;
use crate::record::{failed_row, set_params, skipped_row};
use crate::shading::gbuffer::FULL_BYTES_PER_PIXEL;
use crate::shading::gpu_paths::{Deferred, Path};
use crate::shading::prepass::{self, Accum, LbFormat, PrePass};
use crate::shading::{reference, ShadeSetup};
use crate::timing::{GpuTimer, Stats};
use crate::{CoreError, Result};
const METHODS: &[&str] = &["deferred", "prepass", "prepass_cpu"];

const LIGHT_ACCUM: Axis = Axis::choice(
    cols::LIGHT_ACCUM,
    "how the lights are accumulated: naive (a pass per light) or tiled (compute, 16² tiles)",
    "tiled",
    &["naive", "tiled"],
);
const LIGHT_BUFFER_FORMAT: Axis = Axis::choice(
    cols::LIGHT_BUFFER_FORMAT,
    "the light buffer's format",
    "rgba16f",
    &["rgba8", "rgba16f", "rg11b10"],
);
const SECOND_VIEW: Axis = Axis::bool(
    cols::SECOND_VIEW,
    "render an independent second view in the pre-pass gap",
    false,
);
const THREAD_COUNT: Axis = Axis::int(
    cols::THREAD_COUNT,
    "CPU threads lighting the light buffer",
    1,
    1,
    1024,
);
const OVERLAP: Axis = Axis::bool(
    cols::OVERLAP,
    "light on the CPU while the GPU renders the second view",
    true,
);

fn axes_of(m: &str) -> Vec<Axis> {
    match m {
        "deferred" => vec![LIGHT_ACCUM],
        "prepass" => vec![LIGHT_ACCUM, LIGHT_BUFFER_FORMAT, SECOND_VIEW],
        _ => vec![LIGHT_BUFFER_FORMAT, THREAD_COUNT, OVERLAP],
    }
}

pub struct PrepassStudy;

struct Timed {
    /// Untimed frames before the samples (the stopping rule's warm-up).
    warmup_frames: usize,
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
    let mut lp = crate::measure::FrameLoop::new(&ctx.plan);
    loop {
        timer.begin_frame();
        let t0 = Instant::now();
        frame(&mut timer)?;
        gpu.wait()?;
        let wall = t0.elapsed().as_secs_f64() * 1e3;
        let spans = timer.read_spans(gpu)?;
        let passes: Vec<(String, f64)> = spans.iter().map(|s| (s.0.clone(), s.2 - s.1)).collect();
        gpu.check_lost()?;
        let ms = if timer.enabled() {
            passes.iter().map(|(_, ms)| ms).sum()
        } else {
            wall
        };
        let step = lp.push(ms);
        if let crate::measure::Step::Sample { .. } = step {
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
        if step == (crate::measure::Step::Sample { last: true }) {
            break;
        }
    }
    Ok(Timed {
        warmup_frames: lp.warmup_frames(),
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
        row.set_f(cols::GPU_MS_MEDIAN, g.median)
            .set_f(cols::GPU_MS_MIN, g.min)
            .set_f(cols::GPU_MS_MAX, g.max)
            .set_f(cols::GPU_MS_REL_NOISE, g.rel_noise)
            .set_f(cols::GPU_IDLE_MS, t.idle.median);
    }
    if let Some((gap, busy)) = t.gap {
        row.set_f(cols::GPU_GAP_MS, gap)
            .set_f(cols::GPU_BUSY_IN_GAP_MS, busy);
    }
    row.set_f(cols::CPU_MS_MEDIAN, t.wall.median)
        .set_f(cols::CPU_MS_MIN, t.wall.min)
        .set_f(cols::CPU_MS_MAX, t.wall.max)
        .set_f(cols::FRAME_MS, t.wall.median)
        .set(
            cols::PASS_MS,
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
    fn methods(&self) -> Methods {
        Methods::List(METHODS.to_vec())
    }
    fn axes(&self, method: &str) -> Vec<Axis> {
        axes_of(method)
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
            row.set(cols::METHOD, &pt.method)
                .set(cols::LIGHT_COUNT, scene.lights.len())
                .set(cols::CLAIMS_EXACT, false);
            set_params(&mut row, pt.point.values())?;
            match self.run_point(ctx, &pt.method, &pt.point, &mut row) {
                Ok(Some((img, is_prepass))) => {
                    let e = image_error(&exact, &img, BAD_PIXEL_TOL);
                    row.set_f(cols::RMSE, e.rmse)
                        .set_f(cols::PSNR_DB, e.psnr_db)
                        .set_f(cols::MAX_ABS_ERR, e.max_abs)
                        .set_f(cols::BAD_PIXEL_FRAC, e.bad_pixel_frac)
                        .set_f(cols::BAD_PIXEL_TOL, BAD_PIXEL_TOL)
                        .set(cols::NON_FINITE, e.non_finite)
                        .set_f(cols::REL_ERR_MAX, rel_err_max(&exact, &img));
                    if is_prepass {
                        row.set_f(cols::SPEC_COLOR_LOSS_RMSE, loss).set_f(
                            cols::FORMAT_RMSE,
                            image_error(&packed, &img, BAD_PIXEL_TOL).rmse,
                        );
                    } else {
                        row.set(cols::BYTES_RT_WRITTEN, px * (FULL_BYTES_PER_PIXEL + 16))
                            .set(cols::BYTES_RT_READ, px * FULL_BYTES_PER_PIXEL);
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
    fn run_point(&self, ctx: &GroupCtx<'_>, method: &str, p: &Point, row: &mut Row) -> PointResult {
        let (gpu, scene, gscene) = (ctx.gpu, ctx.scene, ctx.gscene);
        let accum_name = match p.get(LIGHT_ACCUM.name()) {
            Some(_) => p.choice(&LIGHT_ACCUM),
            None => "tiled".to_string(),
        };
        let tiled = accum_name == "tiled";
        if method == "deferred" {
            row.set(cols::LIGHT_ACCUM, &accum_name);
            let path = if tiled {
                row.set(cols::TILE_SIZE, 16).set(cols::CULL_LEVELS, 1);
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
            row.set(cols::BYTES_ALLOCATED, d.bytes_allocated())
                .set(cols::GEOMETRY_PASSES, 1);
            return Ok(Some((d.read_image(gpu)?, false)));
        }
        let fmt = LbFormat::parse(&p.choice(&LIGHT_BUFFER_FORMAT)).map_err(Skip)?;
        row.set(cols::LIGHT_BUFFER_FORMAT, fmt.name());
        let (accum, view2) = if method == "prepass_cpu" {
            let threads = p.int(&THREAD_COUNT) as usize;
            let overlap = p.bool(&OVERLAP);
            row.set(cols::LIGHT_ACCUM, "cpu")
                .set(cols::SECOND_VIEW, true);
            (Accum::Cpu { threads, overlap }, true)
        } else {
            let v2 = p.bool(&SECOND_VIEW);
            row.set(cols::LIGHT_ACCUM, &accum_name);
            if tiled {
                row.set(cols::TILE_SIZE, 16);
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
        row.set(cols::BYTES_RT_WRITTEN, wr)
            .set(cols::BYTES_RT_READ, rd)
            .set(cols::BYTES_ALLOCATED, pp.bytes_allocated())
            .set(cols::GEOMETRY_PASSES, if view2 { 3 } else { 2 });
        let s = &pp.samples[t.warmup_frames.min(pp.samples.len())..];
        if !s.is_empty() {
            row.set_f(cols::LATENCY_MS, median(s.iter().map(|f| f.latency_ms)));
            if matches!(accum, Accum::Cpu { .. }) {
                row.set_f(cols::CPU_LIGHT_MS, median(s.iter().map(|f| f.cpu_light_ms)))
                    .set_f(cols::MAP_WAIT_MS, median(s.iter().map(|f| f.map_wait_ms)))
                    .set(cols::NOTES,
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
