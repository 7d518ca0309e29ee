//! How a suite becomes rows: expand studies into scene × resolution groups (the shard unit),
//! build and upload each scene once, measure the floors, run the study, and hand every row —
//! ok, skipped or failed, never missing — to the sinks.

use scenarios::{Params, Scene, Suite};

use crate::axes::Point;
use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::measure::{measure, set_timing};
use crate::methods;
use crate::record::{cols, Row, Sink, SCHEMA_VERSION};
pub use crate::record::{failed_row, one_line, set_params, skipped_row};
use crate::studies::{self, Group, GroupCtx, PointSpec};
use crate::{CoreError, Result};

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
        let points = studies::points(study.as_ref(), spec).map_err(|e| {
            CoreError::Param(format!(
                "suite '{}' study {si} ({}): {}",
                suite.name,
                spec.kind,
                e.join("; ")
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
/// (`floor_blend`: every fragment blended unordered in hardware: what an engine without OIT
/// pays, the ratio LucidRaster reports.)
pub const FLOORS: &[&str] = &["floor_depth", "floor_opaque", "floor_blend"];

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
    let warmup = if software {
        suite
            .software
            .as_ref()
            .and_then(|s| s.warmup)
            .unwrap_or(suite.warmup)
    } else {
        suite.warmup
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
                .set(cols::WARMUP, warmup)
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
                point: Point::empty(),
            })
            .chain(group.points.iter().cloned())
            .collect();
        let fail_all = |sink: &mut dyn Sink, why: &str, skipped: bool| -> Result<usize> {
            for p in &all_points {
                let mut row = Row::new();
                set_params(&mut row, p.point.values())?;
                let row = if skipped {
                    skipped_row(row, why)
                } else {
                    failed_row(row, why)
                };
                sink.point_done(&meta(row, &p.method, p.given()))?;
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
        let mut ctx = GroupCtx::new(gpu, suite, spec, group, &scene, &gscene, reps, warmup);
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
            let row = match measure(gpu, &gscene, method.as_ref(), &Point::empty(), warmup, reps) {
                Ok(m) => {
                    set_timing(&mut row, &m, &scene.mesh);
                    if *f == "floor_depth" {
                        ctx.floor_ms = m.gpu_ms.map(|s| s.median);
                    }
                    if *f == "floor_blend" {
                        ctx.blend_ms = m.gpu_ms.map(|s| s.median);
                    }
                    row
                }
                Err(e) => failed_row(row, &e.to_string()),
            };
            let mut row = meta(row, f, &Params::new());
            set_x_floor(&mut row, ctx.floor_ms, ctx.blend_ms);
            sink.point_done(&row)?;
            written += 1;
        }
        let study = studies::by_kind(&group.kind).expect("checked in expand");
        let mut done = vec![false; group.points.len()];
        let mut sink_err: Option<CoreError> = None;
        let (floor_ms, blend_ms) = (ctx.floor_ms, ctx.blend_ms);
        let res = {
            let mut emit = |i: usize, mut row: Row| -> Result<()> {
                let p = &group.points[i];
                add_scene(&mut row);
                let mut row = meta(row, &p.method, p.given());
                set_x_floor(&mut row, floor_ms, blend_ms);
                if done[i] {
                    return Err(CoreError::Schema(format!(
                        "point {} emitted twice",
                        group.point_key(&p.method, p.given())
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
                set_params(&mut row, p.point.values())?;
                add_scene(&mut row);
                sink.point_done(&meta(failed_row(row, &why), &p.method, p.given()))?;
                written += 1;
            }
        }
    }
    Ok(written)
}

/// `x_floor` and `x_blend`: the row's median GPU time over the group's floors.
fn set_x_floor(row: &mut Row, floor_ms: Option<f64>, blend_ms: Option<f64>) {
    let Some(g) = row.get_f(cols::GPU_MS_MEDIAN) else {
        return;
    };
    if row.get(cols::STATUS) != Some("ok") {
        return;
    }
    for (col, floor) in [(cols::X_FLOOR, floor_ms), (cols::X_BLEND, blend_ms)] {
        if let Some(f) = floor.filter(|f| *f > 0.0) {
            row.set_f(col, g / f);
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

/// Parses, checks and runs a suite's text on `gpu`, unsharded, and returns every row (tests and
/// tools). A suite with problems is an error listing them all; the row count is checked.
pub fn run_suite(gpu: &Gpu, text: &str, source: &str) -> Result<Vec<Row>> {
    let suite = Suite::parse(text, source)?;
    let problems = crate::check::check_suite(&suite);
    if !problems.is_empty() {
        return Err(CoreError::Param(scenarios::problem::report(&problems)));
    }
    run_checked(gpu, &suite)
}

/// Runs a checked suite on `gpu`, unsharded, into memory.
pub fn run_checked(gpu: &Gpu, suite: &Suite) -> Result<Vec<Row>> {
    let groups = expand(suite, gpu.facts.is_software)?;
    let mut sink = crate::record::VecSink::default();
    let opts = RunOptions {
        run_id: "test".into(),
        git_rev: "test".into(),
        shard: (0, 1),
        save_images: None,
    };
    let written = run(gpu, suite, &groups, &opts, &mut sink)?;
    if written != rows_in(&groups) || sink.0.len() != written {
        return Err(CoreError::Schema(format!(
            "{} rows written for {} points",
            sink.0.len(),
            rows_in(&groups)
        )));
    }
    Ok(sink.0)
}

/// Rows a suite sweeps on a GPU (`software = false`) or a software adapter (for `mfx list`).
pub fn rows_of(suite: &Suite, software: bool) -> usize {
    expand(suite, software).map(|g| rows_in(&g)).unwrap_or(0)
}
