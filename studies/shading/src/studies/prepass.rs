//! The `prepass` study (issue 10): the light pre-pass renderer (`shading::prepass`) against
//! full deferred shading on the same scene — time, render-target bytes, error vs the same f64
//! reference as the `deferred` study, and the specular colour the RGB+A packing loses — and the
//! light buffer computed on CPU cores while the GPU renders an independent view.
//!
//! Methods: `deferred` (axis `light_accum` = naive | tiled), `prepass` (`light_accum`,
//! `light_buffer_format`, `second_view`), `prepass_cpu` (`light_buffer_format`,
//! `thread_count`, `overlap`, `host_work`: the decode, reorder and pack around the lighting on
//! the workers (parallel, the default) or on one thread (serial); always with the independent
//! view). Compare `prepass_cpu` with
//! `prepass(second_view=true)`: the same two views, lit on the GPU.

use super::deferred::{gbuffer_of, rel_err_max};
use crate::gbuffer::FULL_BYTES_PER_PIXEL;
use crate::gpu_paths::{Deferred, Path};
use crate::prepass::{self, Accum, HostWork, LbFormat, PrePass};
use crate::{reference, ShadeSetup};
use bench_core::axes::{Axis, Point};
use bench_core::gpu_scene::GpuScene;
use bench_core::measure::{measure_timed, set_timing, Measured};
use bench_core::record::cols;
use bench_core::record::Row;
use bench_core::record::{failed_row, set_params, skipped_row};
use bench_core::study::{Emit, GroupCtx, Methods, Study, StudyKind};
use bench_core::{CoreError, Result};
use mfx_reference::metrics::{image_error, BAD_PIXEL_TOL};
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

const HOST_WORK: Axis = Axis::choice(
    cols::HOST_WORK,
    "the host work around the CPU lighting (decode, reorder, pack): parallel on the lighting's workers, or serial on one thread (mfx's earlier host)",
    "parallel",
    HostWork::NAMES,
);

fn axes_of(m: &str) -> Vec<Axis> {
    match m {
        "deferred" => vec![LIGHT_ACCUM],
        "prepass" => vec![LIGHT_ACCUM, LIGHT_BUFFER_FORMAT, SECOND_VIEW],
        _ => vec![LIGHT_BUFFER_FORMAT, THREAD_COUNT, OVERLAP, HOST_WORK],
    }
}

pub struct PrepassStudy;

/// The columns a pre-pass or deferred frame's timing gives beyond `set_timing`'s: the frame's
/// wall time, the wall time the GPU was not busy, and the parts the frame reported.
fn set_times<T: ?Sized>(row: &mut Row, m: &Measured<T>) {
    row.set_f(cols::FRAME_MS, m.cpu.median);
    // frame_ms's interval over the kept frames (a verdict on frame_ms needs one).
    let mut wall: Vec<f64> = m
        .samples
        .iter()
        .filter(|s| !s.discarded)
        .map(|s| s.cpu_ms)
        .collect();
    wall.sort_by(|a, b| a.total_cmp(b));
    if let Some((lo, hi)) = mfx_stats::median_ci_order(&wall) {
        row.set_f(cols::FRAME_MS_CI_LO, lo)
            .set_f(cols::FRAME_MS_CI_HI, hi);
    }
    if let Some(idle) = m.idle_median() {
        row.set_f(cols::GPU_IDLE_MS, idle);
    }
    if let (Some(gap), Some(busy)) = (
        m.part_median(cols::GPU_GAP_MS),
        m.part_median(cols::GPU_BUSY_IN_GAP_MS),
    ) {
        row.set_f(cols::GPU_GAP_MS, gap)
            .set_f(cols::GPU_BUSY_IN_GAP_MS, busy);
    }
    if let Some(l) = m.part_median(cols::LATENCY_MS) {
        row.set_f(cols::LATENCY_MS, l);
    }
    if let Some(r) = m.part_median(cols::LIGHT_READY_MS) {
        row.set_f(cols::LIGHT_READY_MS, r);
        if let Some(within) = lit_within_frame(m) {
            row.set(cols::LIT_WITHIN_FRAME, within);
        }
    }
}

/// The light pre-pass chapter's "no added frame of latency", per kept sample: the CPU-lit light
/// buffer was ready (uploaded) before the main view that reads it finished, and that view
/// finished within the frame's own wall time (a design that lit frame N while the GPU drew
/// frame N + 1 would fail the second). `None` where the parts and the kept samples do not
/// line up one to one (nothing to decide from).
fn lit_within_frame<T: ?Sized>(m: &Measured<T>) -> Option<bool> {
    let ready = m.parts.get(&cols::LIGHT_READY_MS)?;
    let latency = m.parts.get(&cols::LATENCY_MS)?;
    let wall: Vec<f64> = m
        .samples
        .iter()
        .filter(|s| !s.discarded)
        .map(|s| s.cpu_ms)
        .collect();
    if ready.is_empty() || ready.len() != latency.len() || latency.len() != wall.len() {
        return None;
    }
    Some(
        ready
            .iter()
            .zip(latency)
            .zip(&wall)
            .all(|((r, l), w)| r <= l && l <= w),
    )
}

impl Study for PrepassStudy {
    fn kind(&self) -> StudyKind {
        StudyKind::Prepass
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
            set_params(&mut row, &pt.point.recorded())?;
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
            let make = |gs: &GpuScene| -> Result<Box<Deferred>> {
                Ok(Box::new(Deferred::new(gpu, scene, gs, path, 0.0, false)?))
            };
            let m = measure_timed(gpu, gscene, &make, &ctx.plan)?;
            set_timing(row, &m, &scene.mesh);
            set_times(row, &m);
            return Ok(Some((m.prepared.read_image(gpu)?, false)));
        }
        let fmt =
            LbFormat::parse(&p.choice(&LIGHT_BUFFER_FORMAT)).map_err(|e| Skip(e.to_string()))?;
        row.set(cols::LIGHT_BUFFER_FORMAT, fmt.name());
        let (accum, view2) = if method == "prepass_cpu" {
            let threads = p.int(&THREAD_COUNT) as usize;
            let overlap = p.bool(&OVERLAP);
            // Checked against NAMES with the suite, before any GPU work.
            let host = HostWork::parse(&p.choice(&HOST_WORK)).unwrap_or_default();
            row.set(cols::LIGHT_ACCUM, "cpu")
                .set(cols::SECOND_VIEW, true)
                .set(cols::HOST_WORK, host.name());
            (
                Accum::Cpu {
                    threads,
                    overlap,
                    host,
                },
                true,
            )
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
        prepass::supports(gpu, fmt, accum).map_err(|e| Skip(e.into()))?;
        // CPU lighting runs inside the frame `measure` times (its wall clock is the frame's):
        // the stopping rule, canary and clock lift apply to the whole frame, and the CPU parts
        // the frame reports are the medians of the same kept samples.
        let make = |gs: &GpuScene| -> Result<Box<PrePass>> {
            Ok(Box::new(PrePass::new(
                gpu, scene, gs, fmt, accum, 0.0, view2,
            )?))
        };
        let m = measure_timed(gpu, gscene, &make, &ctx.plan)?;
        set_timing(row, &m, &scene.mesh);
        set_times(row, &m);
        let (wr, rd) = m.prepared.rt_bytes(gscene.pixels() as u64);
        row.set(cols::BYTES_RT_WRITTEN, wr)
            .set(cols::BYTES_RT_READ, rd);
        if matches!(accum, Accum::Cpu { .. }) {
            if let (Some(light), Some(wait), Some(total)) = (
                m.part_median(cols::CPU_LIGHT_MS),
                m.part_median(cols::MAP_WAIT_MS),
                m.part_median(crate::prepass::CPU_TOTAL_MS),
            ) {
                row.set_f(cols::CPU_LIGHT_MS, light)
                    .set_f(cols::MAP_WAIT_MS, wait)
                    .set(cols::NOTES,
                        format!(
                            "measured: frame_ms = wall clock from the pre-pass submit to both views done; cpu_light_ms = lighting only, decode+light+pack+upload median {total:.3} ms; gpu_gap_ms/gpu_busy_in_gap_ms on the GPU clock (busy > 0 = the second view ran while the CPU lit); readiness = map_async callback + blocking poll(Wait) on the pre-pass submission (no spin); one frame in flight, nothing pipelined across frames; medians of the kept samples",
                        ),
                    );
            }
        }
        Ok(Some((m.prepared.read_image(gpu)?, true)))
    }
}
