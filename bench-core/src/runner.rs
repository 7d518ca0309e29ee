//! How a suite becomes rows: expand studies into scene × resolution groups (the shard unit),
//! build and upload each scene once, measure the floors, run the study, and hand every row —
//! ok, skipped or failed, never missing — to the sinks.

use std::collections::BTreeMap;

use scenarios::{Params, Scene, Suite};

use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::methods::{self, FrameStats, Method, Prepared};
use crate::record::{cols, Row, Sink, SCHEMA_VERSION};
pub use crate::record::{failed_row, one_line, set_params, skipped_row};
use crate::studies::{self, Group, GroupCtx, PointSpec};
use crate::timing::{GpuTimer, Stats};
use crate::{CoreError, Result};

/// The result of timing one method on one scene.
pub struct Measured {
    pub gpu_ms: Option<Stats>,
    pub cpu_ms: Stats,
    /// Median ms per pass label (passes with the same label in one frame are summed).
    pub pass_ms: BTreeMap<String, f64>,
    pub frame: FrameStats,
    pub bytes_allocated: u64,
    pub prepared: Box<dyn Prepared>,
}

fn scope_error(e: Option<wgpu::Error>, what: &str) -> Result<()> {
    match e {
        None => Ok(()),
        Some(wgpu::Error::OutOfMemory { .. }) => Err(CoreError::OutOfMemory(format!(
            "{what}: the GPU ran out of memory"
        ))),
        Some(e) => Err(CoreError::Gpu(format!("{what}: {e}"))),
    }
}

/// Prepares `method` (untimed), runs `warmup` frames, then `reps` timed frames.
pub fn measure(
    gpu: &Gpu,
    scene: &GpuScene,
    method: &dyn Method,
    params: &Params,
    warmup: u32,
    reps: u32,
) -> Result<Measured> {
    gpu.check_lost()?;
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let prepared = method.prepare(gpu, scene, params);
    scope_error(pollster::block_on(oom.pop()), "prepare")?;
    scope_error(pollster::block_on(validation.pop()), "prepare")?;
    let mut prepared = prepared?;
    let bytes_allocated = prepared.bytes_allocated();

    let mut timer = GpuTimer::new(gpu);
    let mut gpu_samples = Vec::new();
    let mut cpu_samples = Vec::new();
    let mut per_label: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut frame = FrameStats::default();
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let mut run = || -> Result<()> {
        for rep in 0..warmup + reps {
            timer.begin_frame();
            let t0 = std::time::Instant::now();
            frame = prepared.frame(gpu, scene, &mut timer)?;
            gpu.wait()?;
            let cpu = t0.elapsed().as_secs_f64() * 1e3;
            let passes = timer.read(gpu)?;
            gpu.check_lost()?;
            if rep >= warmup {
                cpu_samples.push(cpu);
                if timer.enabled() {
                    gpu_samples.push(passes.iter().map(|(_, ms)| ms).sum());
                    let mut frame_labels: BTreeMap<String, f64> = BTreeMap::new();
                    for (l, ms) in passes {
                        *frame_labels.entry(l).or_default() += ms;
                    }
                    for (l, ms) in frame_labels {
                        per_label.entry(l).or_default().push(ms);
                    }
                }
            }
        }
        Ok(())
    };
    let res = run();
    scope_error(pollster::block_on(oom.pop()), "frame")?;
    scope_error(pollster::block_on(validation.pop()), "frame")?;
    res?;
    Ok(Measured {
        gpu_ms: Stats::of(&gpu_samples),
        cpu_ms: Stats::of(&cpu_samples).unwrap_or_default(),
        pass_ms: per_label
            .into_iter()
            .map(|(l, v)| (l, Stats::of(&v).map(|s| s.median).unwrap_or(0.0)))
            .collect(),
        frame,
        bytes_allocated,
        prepared,
    })
}

/// Timing, pass and memory columns of a measured point.
pub fn set_timing(row: &mut Row, m: &Measured, ctx: &GroupCtx<'_>) {
    if let Some(g) = m.gpu_ms {
        row.set_f(cols::GPU_MS_MEDIAN, g.median)
            .set_f(cols::GPU_MS_MIN, g.min)
            .set_f(cols::GPU_MS_MAX, g.max)
            .set_f(cols::GPU_MS_REL_NOISE, g.rel_noise);
        if g.median > 0.0 {
            let secs = g.median * 1e-3 / m.frame.geometry_passes.max(1) as f64;
            row.set_f(
                cols::TRIANGLES_PER_S,
                ctx.scene.mesh.triangle_count() as f64 / secs,
            )
            .set_f(
                cols::VERTICES_PER_S,
                ctx.scene.mesh.indices.len() as f64 / secs,
            );
        }
    }
    row.set_f(cols::CPU_MS_MEDIAN, m.cpu_ms.median)
        .set_f(cols::CPU_MS_MIN, m.cpu_ms.min)
        .set_f(cols::CPU_MS_MAX, m.cpu_ms.max);
    row.set(
        cols::PASS_MS,
        serde_json::to_string(&m.pass_ms).unwrap_or_default(),
    );
    row.set(cols::GEOMETRY_PASSES, m.frame.geometry_passes)
        .set(cols::BYTES_ALLOCATED, m.bytes_allocated);
}

/// Where a sweep runs and how it identifies itself.
pub struct RunOptions {
    pub run_id: String,
    pub git_rev: String,
    /// (I, N) of `--shard I/N`.
    pub shard: (usize, usize),
    /// Folder where studies save each point's image (`--save-images`), or none.
    pub save_images: Option<std::path::PathBuf>,
}

/// Expands every study of the suite into groups, in suite order (deterministic: the shard
/// assignment is group index mod N).
pub fn expand(suite: &Suite, software: bool) -> Result<Vec<Group>> {
    let mut groups = Vec::new();
    for (si, spec) in suite.studies.iter().enumerate() {
        let study = studies::by_kind(&spec.kind).ok_or_else(|| {
            CoreError::Param(format!(
                "suite '{}' study {si}: unknown kind '{}' (known: {})",
                suite.name,
                spec.kind,
                studies::all()
                    .iter()
                    .map(|s| s.kind())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })?;
        let points = study.points(spec).map_err(|e| {
            CoreError::Param(format!(
                "suite '{}' study {si} ({}): {e}",
                suite.name, spec.kind
            ))
        })?;
        if spec.scenes.is_empty() {
            return Err(CoreError::Param(format!(
                "suite '{}' study {si} ({}): no scenes",
                suite.name, spec.kind
            )));
        }
        for scene in &spec.scenes {
            for (w, h) in suite.study_resolutions(spec, software) {
                groups.push(Group {
                    study_index: si,
                    kind: spec.kind.clone(),
                    scene: scene.clone(),
                    width: w,
                    height: h,
                    points: points.clone(),
                });
            }
        }
    }
    Ok(groups)
}

/// The groups of shard I of N.
pub fn shard_groups(groups: Vec<Group>, shard: (usize, usize)) -> Vec<Group> {
    groups
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % shard.1 == shard.0)
        .map(|(_, g)| g)
        .collect()
}

/// Rows per group: the two floors plus the study's points.
pub const FLOORS: &[&str] = &["floor_depth", "floor_opaque"];

pub fn rows_in(groups: &[Group]) -> usize {
    groups.iter().map(|g| g.points.len() + FLOORS.len()).sum()
}

/// Runs the groups, sending every row to `sink`. Returns the number of rows written.
pub fn run(
    gpu: &Gpu,
    suite: &Suite,
    groups: &[Group],
    opts: &RunOptions,
    sink: &mut dyn Sink,
) -> Result<usize> {
    let software = gpu.facts.is_software;
    let reps = if software {
        suite
            .software
            .as_ref()
            .and_then(|s| s.reps)
            .unwrap_or(suite.reps)
    } else {
        suite.reps
    };
    let mut written = 0;
    for group in groups {
        let meta = |mut row: Row, method: &str, params: &Params| -> Row {
            let f = &gpu.facts;
            row.set(cols::SCHEMA, SCHEMA_VERSION)
                .set(cols::RUN_ID, &opts.run_id)
                .set(cols::GIT_REV, &opts.git_rev)
                .set(
                    cols::TIMESTAMP_UTC,
                    chrono::Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, true),
                )
                .set(cols::SUITE, &suite.name)
                .set(cols::STUDY, &group.kind)
                .set(cols::SHARD, opts.shard.0)
                .set(cols::SHARDS, opts.shard.1)
                .set(cols::POINT_KEY, group.point_key(method, params))
                .set(cols::ADAPTER, &f.name)
                .set(cols::BACKEND, &f.backend)
                .set(cols::DEVICE_TYPE, &f.device_type)
                .set(cols::DRIVER, &f.driver)
                .set(cols::DRIVER_INFO, &f.driver_info)
                .set(cols::ADAPTER_FEATURES, &f.features)
                .set(cols::WIDTH, group.width)
                .set(cols::HEIGHT, group.height)
                .set(cols::REPS, reps)
                .set(cols::WARMUP, suite.warmup)
                .set(cols::SCENE, &group.scene.generator)
                .set(cols::SCENE_LABEL, group.scene.label());
            if row.get(cols::METHOD).is_none() {
                row.set(cols::METHOD, method);
            }
            if row.get(cols::STATUS).is_none() {
                row.set(cols::STATUS, "ok");
            }
            row
        };
        let all_points: Vec<PointSpec> = FLOORS
            .iter()
            .map(|f| PointSpec {
                method: f.to_string(),
                params: Params::new(),
            })
            .chain(group.points.iter().cloned())
            .collect();
        let fail_all = |sink: &mut dyn Sink, why: &str, skipped: bool| -> Result<usize> {
            for p in &all_points {
                let mut row = Row::new();
                set_params(&mut row, &p.params)?;
                let row = if skipped {
                    skipped_row(row, why)
                } else {
                    failed_row(row, why)
                };
                sink.point_done(&meta(row, &p.method, &p.params))?;
            }
            Ok(all_points.len())
        };
        let scene: Scene = match group.scene.build() {
            Ok(s) => s,
            Err(e) => {
                written += fail_all(sink, &format!("scene: {e}"), false)?;
                continue;
            }
        };
        if software {
            if let Some(max) = suite.software.as_ref().and_then(|s| s.max_triangles) {
                if scene.mesh.triangle_count() as u64 > max {
                    let why = format!(
                        "{} triangles exceed this suite's software-adapter limit of {max}",
                        scene.mesh.triangle_count()
                    );
                    written += fail_all(sink, &why, true)?;
                    continue;
                }
            }
        }
        if let Err(e) = gpu.check_lost() {
            written += fail_all(sink, &e.to_string(), false)?;
            continue;
        }
        let gscene = GpuScene::upload(gpu, &scene, group.width, group.height);
        let spec = &suite.studies[group.study_index];
        let mut ctx = GroupCtx::new(gpu, suite, spec, group, &scene, &gscene, reps, suite.warmup);
        ctx.images_dir = opts.save_images.clone();
        let add_scene = |row: &mut Row| {
            row.set(cols::TRIANGLES, scene.mesh.triangle_count())
                .set(cols::VERTICES, scene.mesh.vertex_count());
        };
        // Floors first: they are every other row's yardstick.
        for f in FLOORS {
            let method = methods::by_name(f).expect("floor methods exist");
            let mut row = Row::new();
            row.set(cols::METHOD, *f).set(cols::EXACT, false);
            add_scene(&mut row);
            let row = match measure(
                gpu,
                &gscene,
                method.as_ref(),
                &Params::new(),
                suite.warmup,
                reps,
            ) {
                Ok(m) => {
                    set_timing(&mut row, &m, &ctx);
                    if *f == "floor_depth" {
                        ctx.floor_ms = m.gpu_ms.map(|s| s.median);
                    }
                    row
                }
                Err(e) => failed_row(row, &e.to_string()),
            };
            let mut row = meta(row, f, &Params::new());
            set_x_floor(&mut row, ctx.floor_ms);
            sink.point_done(&row)?;
            written += 1;
        }
        let study = studies::by_kind(&group.kind).expect("checked in expand");
        let mut done = vec![false; group.points.len()];
        let mut sink_err: Option<CoreError> = None;
        let floor_ms = ctx.floor_ms;
        let res = {
            let mut emit = |i: usize, mut row: Row| -> Result<()> {
                let p = &group.points[i];
                add_scene(&mut row);
                let mut row = meta(row, &p.method, &p.params);
                set_x_floor(&mut row, floor_ms);
                if done[i] {
                    return Err(CoreError::Schema(format!(
                        "point {} emitted twice",
                        group.point_key(&p.method, &p.params)
                    )));
                }
                done[i] = true;
                if let Err(e) = sink.point_done(&row) {
                    sink_err = Some(CoreError::Io(e.to_string()));
                    return Err(e);
                }
                Ok(())
            };
            study.run_group(&ctx, &mut emit)
        };
        if let Some(e) = sink_err {
            return Err(e);
        }
        written += done.iter().filter(|d| **d).count();
        // A study that stopped early still owes a row for every point it did not emit.
        let why = match &res {
            Ok(()) => {
                "the study emitted no row for this point (a bug: reported, not hidden)".to_string()
            }
            Err(e) => format!("study stopped: {e}"),
        };
        for (i, p) in group.points.iter().enumerate() {
            if !done[i] {
                let mut row = Row::new();
                set_params(&mut row, &p.params)?;
                add_scene(&mut row);
                sink.point_done(&meta(failed_row(row, &why), &p.method, &p.params))?;
                written += 1;
            }
        }
    }
    Ok(written)
}

fn set_x_floor(row: &mut Row, floor_ms: Option<f64>) {
    if let (Some(f), Some(g)) = (
        floor_ms,
        row.get(cols::GPU_MS_MEDIAN)
            .and_then(|s| s.parse::<f64>().ok()),
    ) {
        if f > 0.0 && row.get(cols::STATUS) == Some("ok") {
            row.set_f(cols::X_FLOOR, g / f);
        }
    }
}

/// `git describe`-like revision of the working tree, or `unknown`.
pub fn git_rev() -> String {
    // A revision embedded at build time wins: the device machine gets a copy of the working
    // tree whose `.git` may be a stale snapshot, so asking git there names the wrong commit.
    if let Some(rev) = option_env!("MFX_GIT_REV") {
        return rev.to_string();
    }
    let out = std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output();
    match out {
        Ok(o) if o.status.success() => {
            let rev = String::from_utf8_lossy(&o.stdout).trim().to_string();
            let dirty = std::process::Command::new("git")
                .args(["status", "--porcelain", "--untracked-files=no"])
                .output()
                .map(|o| !o.stdout.is_empty())
                .unwrap_or(false);
            if dirty {
                format!("{rev}+dirty")
            } else {
                rev
            }
        }
        _ => "unknown".to_string(),
    }
}
