//! The `deferred` study (issue 6): tiled deferred shading with screen-space classification and
//! tile light culling, on the GPU and on CPU cores, judged against the brute-force f64
//! reference of the same G-buffer (`shading::reference`).
//!
//! Paths (`methods` in the suite): `naive`, `volumes`, `tiled`, `classified`, `uber`,
//! `cpu_tiled` (see `shading::gpu_paths` and `shading::cpu_tiled`). Axes: `tile_size`,
//! `cull_levels`, `attenuation_threshold` (tiled, volumes, cpu_tiled), `thread_count`,
//! `quad_skip`, `spec_skip`, `cone_cull` and `diffuse_skip` (cpu_tiled), `diffuse_only_frac`
//! (every path: the fraction of lights flagged diffuse-only, which changes the image, so the
//! reference and the naive time are per fraction), `sun_shadow` (naive, classified, uber:
//! `off`, or `taps8`: the sun through a shadow map with an 8-tap filter, Split/Second's
//! expensive soft-shadow class; the reference and the naive time are per value too), `msaa`
//! (naive, classified, uber: `off`, or `x2`: a 2×MSAA G-buffer, Split/Second's MSAA-edge class;
//! `x4` the same with 4 samples, lavapipe's only MSAA count; judged against the average of the
//! f64 shading of each read-back sample). The light
//! count is a scene parameter
//! (`city(lights=N)`), recorded per row.
//! `naive` runs first in each group so every row carries `speedup_vs_naive`.
//!
//! `cpu_tiled` rows also carry BF3's per-phase costs (`cpu_cull_ms`, `cpu_unpack_ms`,
//! `cpu_shade_ms`, `cpu_pack_ms`, thread-summed) and the light loop's cost per (light, quad)
//! evaluation (`shade_ns_per_light_quad`: diffuse-only against specular lights, BF3's "2×+"),
//! from one extra frame with phase clocks after the timed ones (the clocks stay out of
//! `cpu_light_ms`).
//!
//! Study options: `cpu_reps` (timed CPU frames per point, default 3: a single-thread frame at
//! 4K is seconds).

use std::collections::HashMap;

use scenarios::Scene;

use crate::cpu_tiled::{self, CpuOptions};
use crate::gbuffer::GBufferPass;
use crate::gpu_paths::{self, Deferred, Path};
use crate::msaa;
use crate::sun_shadow::{self, SunShadow};
use crate::{class, reference, GBuffer, ShadeSetup};
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::measure::{measure_timed, set_timing};
use bench_core::record::Row;
use bench_core::record::{cols, Flag};
use bench_core::record::{error_row, failed_row, set_params, skipped_row};
use bench_core::study::{Emit, GroupCtx, Methods, Opt, Study, StudyKind};
use bench_core::timing::{GpuTimer, Stats};
use bench_core::{Result, Unsupported};
use mfx_reference::metrics::{image_error, BAD_PIXEL_TOL};
pub const PATHS: &[&str] = &[
    "naive",
    "volumes",
    "tiled",
    "classified",
    "uber",
    "cpu_tiled",
];

const TILE_SIZE: Axis = Axis::int(
    cols::TILE_SIZE,
    "tiled: culling tile side in pixels",
    16,
    1,
    4096,
);
const GPU_CULL_LEVELS: Axis = Axis::int(
    cols::CULL_LEVELS,
    "tiled: culling levels (1 = per tile; 2 = 64² tiles then 32×16 sub-tiles)",
    1,
    0,
    16,
);
const CPU_CULL_LEVELS: Axis = Axis::int(
    cols::CULL_LEVELS,
    "cpu_tiled: 1 = 64² tiles; 2 = then 32×16 sub-tiles (BF3)",
    2,
    1,
    2,
);
const THRESHOLD: Axis = Axis::float(
    cols::ATTENUATION_THRESHOLD,
    "τ: cull a light from a tile where its peak contribution is ≤ τ everywhere (0: only beyond its range)",
    0.0,
    0.0,
    f64::MAX,
);
const DIFFUSE_ONLY_FRAC: Axis = Axis::float(
    cols::DIFFUSE_ONLY_FRAC,
    "fraction of the scene's lights flagged diffuse-only",
    0.0,
    0.0,
    1.0,
);
const SUN_SHADOW: Axis = Axis::choice(
    cols::SUN_SHADOW,
    "naive, classified, uber: the sun through a shadow map with an 8-tap filter (taps8; the classified path filters only its fade tiles) or unshadowed (off)",
    "off",
    sun_shadow::Mode::NAMES,
);
const MSAA: Axis = Axis::choice(
    cols::MSAA,
    "naive, classified, uber: a 2×MSAA G-buffer (x2; naive and uber shade both samples of every pixel, classified only in MSAA-edge tiles), 4× (x4, the same) or one sample (off)",
    "off",
    msaa::Mode::NAMES,
);
const THREAD_COUNT: Axis = Axis::int(cols::THREAD_COUNT, "CPU worker threads", 1, 1, 1024);
const QUAD_SKIP: Axis = Axis::bool(
    cols::QUAD_SKIP,
    "skip a light for a 4×4 quad when all 16 attenuations are 0",
    true,
);
const SPEC_SKIP: Axis = Axis::bool(cols::SPEC_SKIP, "no-specular fast path per 4×4 quad", true);
const CONE_CULL: Axis = Axis::bool(cols::CONE_CULL, "normal-cone cull per 32×16 sub-tile", true);
const DIFFUSE_SKIP: Axis = Axis::bool(
    cols::DIFFUSE_SKIP,
    "skip the specular term of diffuse-only lights",
    true,
);
const LIGHT_LOOP: Axis = Axis::choice(
    cols::LIGHT_LOOP,
    "cpu_tiled: the light loop of a 4×4 quad: bf3 (DICE's SoA loop, all 16 lanes per light with masks after a whole-quad attenuation branch) or mfx (per-lane early-outs); same image",
    "bf3",
    cpu_tiled::LightLoop::NAMES,
);
const CLASSIFY: Axis = Axis::choice(
    cols::CLASSIFY,
    "cpu_tiled: BF3's material classification: materials (a code permutation per 32×16 sub-tile from its material + light mask) or none (the catch-all übershader); same image",
    "none",
    cpu_tiled::Classify::NAMES,
);
const PHASE_REPS: Opt = Opt {
    name: "phase_reps",
    doc: "cpu_tiled: phase-clock frames per point (the cpu_*_ms phases and shade_ns_per_light_quad are their medians; from 6 on, shade_ns_per_light_quad carries its 95 % interval)",
    kind: scenarios::ValueKind::Int {
        default: 1,
        min: 1,
        max: 10_000,
    },
};
const CPU_REPS: Opt = Opt {
    name: "cpu_reps",
    doc: "timed repetitions of the CPU lighting paths",
    kind: scenarios::ValueKind::Int {
        default: 3,
        min: 1,
        max: 100_000,
    },
};

/// The axes a path reads.
fn axes_of(path: &str) -> Vec<Axis> {
    match path {
        "tiled" => vec![TILE_SIZE, GPU_CULL_LEVELS, THRESHOLD, DIFFUSE_ONLY_FRAC],
        "volumes" => vec![THRESHOLD, DIFFUSE_ONLY_FRAC],
        "cpu_tiled" => vec![
            THREAD_COUNT,
            CPU_CULL_LEVELS,
            THRESHOLD,
            QUAD_SKIP,
            SPEC_SKIP,
            CONE_CULL,
            DIFFUSE_SKIP,
            DIFFUSE_ONLY_FRAC,
            LIGHT_LOOP,
            CLASSIFY,
        ],
        "naive" | "classified" | "uber" => vec![DIFFUSE_ONLY_FRAC, SUN_SHADOW, MSAA],
        _ => vec![DIFFUSE_ONLY_FRAC],
    }
}

/// The sun shadow of a point (off for the paths that do not read it).
fn shadow_mode(point: &Point) -> sun_shadow::Mode {
    match point.get(SUN_SHADOW.name()) {
        Some(_) => sun_shadow::Mode::parse(&point.choice(&SUN_SHADOW)).unwrap_or_default(),
        None => sun_shadow::Mode::Off,
    }
}

/// The G-buffer samples of a point (off for the paths that do not read it).
fn msaa_mode(point: &Point) -> msaa::Mode {
    match point.get(MSAA.name()) {
        Some(_) => msaa::Mode::parse(&point.choice(&MSAA)).unwrap_or_default(),
        None => msaa::Mode::Off,
    }
}

/// Renders the multisampled G-buffer once (untimed) and reads every sample back: the MSAA
/// reference's input.
fn gbuffer_samples(
    gpu: &Gpu,
    scene: &Scene,
    gscene: &GpuScene,
    ms: msaa::Mode,
) -> Result<Vec<GBuffer>> {
    msaa::read_samples(
        gpu,
        &render_gbuffer(gpu, scene, gscene, false, ms.samples())?,
    )
}

/// Renders a G-buffer of `samples` samples once, untimed, and waits for it.
fn render_gbuffer(
    gpu: &Gpu,
    scene: &Scene,
    gscene: &GpuScene,
    prepass: bool,
    samples: u32,
) -> Result<GBufferPass> {
    let mut alloc = AllocCounter::default();
    let gb = GBufferPass::new_ms(gpu, scene, gscene, prepass, samples, &mut alloc);
    let mut timer = GpuTimer::new(gpu);
    timer.begin_frame();
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    gb.encode(&mut enc, gscene, &mut timer, "gbuffer");
    gpu.queue.submit([enc.finish()]);
    gpu.wait()?;
    Ok(gb)
}

/// τ of a point (0 for the paths that do not read it).
fn threshold(point: &Point) -> f64 {
    match point.get(THRESHOLD.name()) {
        Some(_) => point.float(&THRESHOLD),
        None => 0.0,
    }
}

fn gpu_path(name: &str, point: &Point) -> std::result::Result<Path, Unsupported> {
    Ok(match name {
        "naive" => Path::Naive,
        "volumes" => Path::Volumes,
        "classified" => Path::Classified { uber: false },
        "uber" => Path::Classified { uber: true },
        "tiled" => Path::Tiled {
            tile: point.int(&TILE_SIZE) as u32,
            levels: point.int(&GPU_CULL_LEVELS) as u32,
        },
        other => {
            return Err(Unsupported::new(format!(
                "'{other}' is not a GPU shading path"
            )))
        }
    })
}

/// Renders the G-buffer once (untimed) and reads it back: the input of the reference and of
/// the CPU paths.
pub fn gbuffer_of(gpu: &Gpu, scene: &Scene, gscene: &GpuScene, prepass: bool) -> Result<GBuffer> {
    render_gbuffer(gpu, scene, gscene, prepass, 1)?.read(gpu)
}

pub fn rel_err_max(r: &[[f64; 4]], g: &[[f32; 4]]) -> f64 {
    let mut m = 0.0f64;
    for (a, b) in r.iter().zip(g) {
        for c in 0..4 {
            let e = (b[c] as f64 - a[c]).abs() / a[c].abs().max(1.0);
            m = m.max(if e.is_finite() { e } else { f64::INFINITY });
        }
    }
    m
}

fn set_error(row: &mut Row, reference: &[[f64; 4]], img: &[[f32; 4]]) {
    let e = image_error(reference, img, BAD_PIXEL_TOL);
    row.set_f(cols::RMSE, e.rmse)
        .set_f(cols::PSNR_DB, e.psnr_db)
        .set_f(cols::MAX_ABS_ERR, e.max_abs)
        .set_f(cols::BAD_PIXEL_FRAC, e.bad_pixel_frac)
        .set_f(cols::BAD_PIXEL_TOL, BAD_PIXEL_TOL)
        .set(cols::NON_FINITE, e.non_finite)
        .set_f(cols::REL_ERR_MAX, rel_err_max(reference, img));
    if e.non_finite > 0 {
        // Added: set_timing may already have flagged the row noisy or throttled.
        row.add_flag(Flag::Precision);
    }
}

/// What changes a point's image: the diffuse-only fraction (its bits), the sun shadow and the
/// G-buffer's samples.
type ImageKey = (u64, sun_shadow::Mode, msaa::Mode);

pub struct DeferredStudy;

impl Study for DeferredStudy {
    fn kind(&self) -> StudyKind {
        StudyKind::Deferred
    }
    fn describe(&self) -> &'static str {
        "deferred shading paths (naive, light volumes, GPU tiled, classified, CPU tiled) vs the f64 reference"
    }
    fn methods(&self) -> Methods {
        Methods::List(PATHS.to_vec())
    }
    fn axes(&self, path: &str) -> Vec<Axis> {
        axes_of(path)
    }
    fn options(&self) -> Vec<Opt> {
        vec![CPU_REPS, PHASE_REPS]
    }

    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
        let (gpu, scene, gscene) = (ctx.gpu, ctx.scene, ctx.gscene);
        let setup0 = ShadeSetup::new(scene, gscene.width, gscene.height);
        let gb = gbuffer_of(gpu, scene, gscene, false)?;
        // The diffuse-only fraction and the sun shadow change the image: a setup, a reference
        // and a naive time per (fraction bits, shadow).
        let mut references: HashMap<ImageKey, (ShadeSetup, Vec<[f64; 4]>)> = HashMap::new();
        // The sun's map as the paths render it (deterministic: each path renders the same),
        // read back once for the reference; `None` without a sun.
        let wants_shadow = ctx
            .group
            .points
            .iter()
            .any(|p| shadow_mode(&p.point) != sun_shadow::Mode::Off);
        // The multisampled G-buffers' samples (deterministic, as the paths render them), read
        // back once per sample count.
        let mut ms_samples: HashMap<msaa::Mode, Vec<GBuffer>> = HashMap::new();
        let shadow_map = if wants_shadow {
            let mut alloc = AllocCounter::default();
            SunShadow::new(gpu, scene, gscene, &mut alloc)?.map(|s| s.map)
        } else {
            None
        };
        let cpu_reps = CPU_REPS.int(ctx.study) as u32;
        let phase_reps = PHASE_REPS.int(ctx.study) as usize;
        let mut order: Vec<usize> = (0..ctx.group.points.len()).collect();
        order.sort_by_key(|&i| ctx.group.points[i].method != "naive");
        let mut naive_by_frac: HashMap<ImageKey, f64> = HashMap::new();
        for i in order {
            let pt = &ctx.group.points[i];
            let mut row = Row::new();
            row.set(cols::METHOD, &pt.method)
                .set(cols::LIGHT_COUNT, scene.lights.len());
            set_params(&mut row, &pt.point.recorded())?;
            let tau = threshold(&pt.point);
            row.set(cols::CLAIMS_EXACT, tau == 0.0);
            let frac = pt.point.float(&DIFFUSE_ONLY_FRAC);
            row.set_f(cols::DIFFUSE_ONLY_FRAC, frac);
            let shadow = shadow_mode(&pt.point);
            if pt.point.get(SUN_SHADOW.name()).is_some() {
                row.set(cols::SUN_SHADOW, shadow.name());
            }
            let ms = msaa_mode(&pt.point);
            if pt.point.get(MSAA.name()).is_some() {
                row.set(cols::MSAA, ms.name());
            }
            if ms != msaa::Mode::Off && shadow != sun_shadow::Mode::Off {
                emit(
                    i,
                    skipped_row(
                        row,
                        &format!(
                            "msaa = {} with sun_shadow = {} is not built (each is tested alone)",
                            ms.name(),
                            shadow.name()
                        ),
                    ),
                )?;
                continue;
            }
            if ms != msaa::Mode::Off {
                if let Err(why) = msaa::supported(gpu, ms) {
                    emit(i, skipped_row(row, &why))?;
                    continue;
                }
                if let std::collections::hash_map::Entry::Vacant(e) = ms_samples.entry(ms) {
                    e.insert(gbuffer_samples(gpu, scene, gscene, ms)?);
                }
            }
            if shadow != sun_shadow::Mode::Off && scene.sun.is_none() {
                emit(
                    i,
                    skipped_row(
                        row,
                        &format!(
                            "sun_shadow = {} needs a sun; this scene has none",
                            shadow.name()
                        ),
                    ),
                )?;
                continue;
            }
            let key = (frac.to_bits(), shadow, ms);
            let (setup, reference) = &*references.entry(key).or_insert_with(|| {
                let s = setup0
                    .clone()
                    .with_diffuse_only(frac)
                    .with_sun_shadow(match shadow {
                        sun_shadow::Mode::Off => None,
                        sun_shadow::Mode::Taps8 => shadow_map.clone(),
                    });
                let r = match ms_samples.get(&ms) {
                    Some(samples) if ms != msaa::Mode::Off => msaa::reference(&s, samples),
                    _ => reference::shade(&s, &gb),
                };
                (s, r)
            });
            let naive_ms = naive_by_frac.get(&key).copied();
            if pt.method == "cpu_tiled" {
                let threads = pt.point.int(&THREAD_COUNT) as usize;
                let levels = pt.point.int(&CPU_CULL_LEVELS);
                let quad_skip = pt.point.bool(&QUAD_SKIP);
                let spec_skip = pt.point.bool(&SPEC_SKIP);
                let cone_cull = pt.point.bool(&CONE_CULL);
                let diffuse_skip = pt.point.bool(&DIFFUSE_SKIP);
                // Checked against NAMES with the suite, before any GPU work.
                let light_loop =
                    cpu_tiled::LightLoop::parse(&pt.point.choice(&LIGHT_LOOP)).unwrap_or_default();
                row.set(cols::LIGHT_LOOP, light_loop.name());
                let classify =
                    cpu_tiled::Classify::parse(&pt.point.choice(&CLASSIFY)).unwrap_or_default();
                row.set(cols::CLASSIFY, classify.name());
                row.set(cols::TILE_SIZE, 64)
                    .set(cols::QUAD_SKIP, quad_skip)
                    .set(cols::SPEC_SKIP, spec_skip)
                    .set(cols::CONE_CULL, cone_cull)
                    .set(cols::DIFFUSE_SKIP, diffuse_skip);
                let lights = setup.gpu_lights(tau);
                let o = CpuOptions {
                    classify,
                    force_perm: None,
                    light_loop,
                    tile: 64,
                    sub: (levels == 2).then_some((32, 16)),
                    threads,
                    quad_skip,
                    spec_skip,
                    cone_cull,
                    cone_margin: cpu_tiled::CONE_MARGIN,
                    diffuse_skip,
                    keep_lists: false,
                    light_buffer: false,
                    phase_times: false,
                    parallel_reorder: false,
                };
                let mut samples = Vec::new();
                let mut last = None;
                for rep in 0..1 + cpu_reps {
                    let r = cpu_tiled::shade(setup, &gb, &lights, &o);
                    if rep > 0 {
                        samples.push(r.ms);
                    }
                    last = Some(r);
                }
                let r = last.expect("at least one frame");
                let st = Stats::of(&samples).unwrap_or_default();
                // Phase-clock frames after the timed ones (the clocks stay out of cpu_light_ms).
                let phased: Vec<(cpu_tiled::Phases, u64)> = (0..phase_reps)
                    .filter_map(|_| {
                        let r = cpu_tiled::shade(
                            setup,
                            &gb,
                            &lights,
                            &CpuOptions {
                                phase_times: true,
                                ..o
                            },
                        );
                        Some((r.phases?, r.quad_evals))
                    })
                    .collect();
                set_phases(&mut row, &phased);
                // No GPU frame to time: CPU lighting of a G-buffer read back once, timed by its
                // own fixed count (a single-thread 4K frame takes seconds, too long for the
                // stopping rule's samples), so the row says that instead of the plan's rule.
                row.set_f(cols::CPU_LIGHT_MS, st.median)
                    .set(cols::SAMPLES, samples.len())
                    .set(
                        cols::TIMING_RULE,
                        format!(
                            "CPU only: 1 untimed then {cpu_reps} timed frames (cpu_reps), median wall clock; no GPU work, so no stopping rule, canary or clock lift"
                        ),
                    );
                let pairs = (r.quad_skips + r.quad_evals).max(1);
                row.set_f(cols::QUAD_SKIP_FRAC, r.quad_skips as f64 / pairs as f64)
                    .set_f(
                        cols::SPEC_SKIP_FRAC,
                        r.spec_skipped_quads as f64 / r.quads.max(1) as f64,
                    )
                    .set_f(
                        cols::CONE_CULL_FRAC,
                        r.cone_culls as f64 / r.cone_tests.max(1) as f64,
                    )
                    .set_f(
                        cols::DIFFUSE_SKIP_FRAC,
                        r.diffuse_skips as f64 / r.quad_evals.max(1) as f64,
                    );
                let regions: u64 = r.perm_regions.iter().sum();
                let ubershader = r.perm_regions[cpu_tiled::perm::ALL as usize];
                row.set_f(
                    cols::PERM_NARROW_FRAC,
                    (regions - ubershader) as f64 / regions.max(1) as f64,
                )
                .set(
                    cols::PERMUTATIONS,
                    r.perm_regions.iter().filter(|&&n| n > 0).count(),
                );
                set_tile_stats(&mut row, &r.tile_counts);
                if let Some(n) = naive_ms {
                    if st.median > 0.0 {
                        row.set_f(cols::SPEEDUP_VS_NAIVE, n / st.median);
                    }
                }
                set_error(&mut row, reference, &r.image);
                row.set(
                    cols::NOTES,
                    if phase_reps == 1 {
                        format!("cpu_reps={cpu_reps}; G-buffer read back once, untimed; cpu_*_ms phases from one more frame with phase clocks")
                    } else {
                        format!("cpu_reps={cpu_reps}; G-buffer read back once, untimed; cpu_*_ms phases and shade_ns_per_light_quad: medians of {phase_reps} more frames with phase clocks")
                    },
                );
                emit(i, row)?;
                continue;
            }
            let path = match gpu_path(&pt.method, &pt.point) {
                Ok(p) => p,
                Err(e) => {
                    emit(i, skipped_row(row, &e))?;
                    continue;
                }
            };
            if let Path::Tiled { tile, levels } = path {
                row.set(cols::TILE_SIZE, tile)
                    .set(cols::CULL_LEVELS, levels);
            }
            if let Err(why) = gpu_paths::supports(gpu, path) {
                emit(i, skipped_row(row, &why))?;
                continue;
            }
            let make = |gs: &GpuScene| -> Result<Box<Deferred>> {
                Ok(Box::new(Deferred::new_with(
                    gpu, scene, gs, path, tau, false, frac, shadow, ms,
                )?))
            };
            let meas = match measure_timed(gpu, gscene, &make, &ctx.plan) {
                Ok(m) => m,
                Err(e) => {
                    emit(i, error_row(row, &e))?;
                    continue;
                }
            };
            set_timing(&mut row, &meas, &ctx.scene.mesh);
            let g = meas.gpu_median();
            if pt.method == "naive" && naive_ms.is_none() {
                if let Some(g) = g {
                    naive_by_frac.insert(key, g);
                }
            }
            let naive_ms = naive_by_frac.get(&key).copied();
            if let (Some(n), Some(g)) = (naive_ms, g) {
                if g > 0.0 {
                    row.set_f(cols::SPEEDUP_VS_NAIVE, n / g);
                }
            }
            // The last timed frame's output and path-specific facts.
            let dd = &meas.prepared;
            match dd.read_image(gpu) {
                Ok(img) => set_error(&mut row, reference, &img),
                Err(e) => {
                    emit(i, failed_row(row, &format!("readback: {e}")))?;
                    continue;
                }
            }
            row.set(cols::PERMUTATIONS, dd.permutations);
            if let Some(c) = dd.tile_counts(gpu)? {
                set_tile_stats(&mut row, &c);
            }
            if let Some((ids, counts, _, _)) = dd.classification(gpu)? {
                row.set(
                    cols::CLASS_IDS_PRESENT,
                    counts.iter().filter(|&&c| c > 0).count(),
                );
                if shadow != sun_shadow::Mode::Off {
                    let fade = ids.iter().filter(|&&id| id & class::FADE != 0).count();
                    row.set_f(
                        cols::SHADOW_FADE_TILE_FRAC,
                        fade as f64 / ids.len().max(1) as f64,
                    );
                }
                if ms != msaa::Mode::Off {
                    let edge = ids.iter().filter(|&&id| id & class::EDGE != 0).count();
                    row.set_f(
                        cols::MSAA_EDGE_TILE_FRAC,
                        edge as f64 / ids.len().max(1) as f64,
                    );
                }
            }
            emit(i, row)?;
        }
        Ok(())
    }
}

/// The phase-clock frames' columns (ns → ms; per-evaluation cost in ns): each the median over
/// the frames (one frame: its value), and the per-evaluation cost's 95 % interval of the median
/// from 6 frames on (issue 45 item 1: a verdict on a CPU metric carries an interval).
fn set_phases(row: &mut Row, frames: &[(cpu_tiled::Phases, u64)]) {
    if frames.is_empty() {
        return;
    }
    let med = |f: &dyn Fn(&cpu_tiled::Phases) -> u64| {
        let mut v: Vec<f64> = frames.iter().map(|(p, _)| f(p) as f64 * 1e-6).collect();
        v.sort_by(|a, b| a.total_cmp(b));
        mfx_stats::median_of_sorted(&v)
    };
    row.set_f(cols::CPU_CULL_MS, med(&|p| p.cull))
        .set_f(cols::CPU_UNPACK_MS, med(&|p| p.unpack))
        .set_f(cols::CPU_SHADE_MS, med(&|p| p.shade()))
        .set_f(cols::CPU_PACK_MS, med(&|p| p.pack))
        .set_f(cols::CPU_PHASES_MS, med(&|p| p.total()));
    let mut per: Vec<f64> = frames
        .iter()
        .filter(|(_, evals)| *evals > 0)
        .map(|(p, evals)| p.lights as f64 / *evals as f64)
        .collect();
    if per.is_empty() {
        return;
    }
    per.sort_by(|a, b| a.total_cmp(b));
    row.set_f(
        cols::SHADE_NS_PER_LIGHT_QUAD,
        mfx_stats::median_of_sorted(&per),
    );
    if let Some((lo, hi)) = mfx_stats::median_ci_order(&per) {
        row.set_f(cols::SHADE_NS_PER_LIGHT_QUAD_CI_LO, lo)
            .set_f(cols::SHADE_NS_PER_LIGHT_QUAD_CI_HI, hi);
    }
}

fn set_tile_stats(row: &mut Row, counts: &[u32]) {
    let n = counts.len().max(1) as f64;
    row.set_f(
        cols::LIGHTS_PER_TILE_MEAN,
        counts.iter().map(|&c| c as f64).sum::<f64>() / n,
    )
    .set(
        cols::LIGHTS_PER_TILE_MAX,
        counts.iter().max().copied().unwrap_or(0),
    );
}

#[cfg(test)]
mod flag_tests {
    use super::*;

    #[test]
    fn a_non_finite_image_adds_precision_and_keeps_an_earlier_noisy() {
        let mut row = Row::new();
        row.add_flag(Flag::Noisy);
        set_error(&mut row, &[[0.5; 4]; 2], &[[0.5; 4], [f32::NAN; 4]]);
        assert!(
            row.has_flag(Flag::Precision) && row.has_flag(Flag::Noisy),
            "{}",
            row.flags()
        );
    }
}
