//! How a suite becomes rows: expand studies into scene × resolution groups (the shard unit),
//! build and upload each scene once, measure the floors, run the study, and hand every row —
//! ok, skipped or failed, never missing — to the sinks.

use scenarios::{Params, Scene, Suite};

use crate::axes::Point;
use crate::floors::Floor;
use crate::gpu::Gpu;
use crate::gpu_scene::GpuScene;
use crate::measure::{measure_timed, set_timing, TimingPlan};
use crate::record::{cols, Row, Sink, Status, SCHEMA_VERSION};
pub use crate::record::{error_row, failed_row, one_line, set_params, skipped_row};
use crate::study::{by_kind, points, Group, GroupCtx, PointSpec, Study};
use crate::{CoreError, Result};

/// Where a sweep runs and how it identifies itself.
#[derive(Clone, Default)]
pub struct RunOptions {
    pub run_id: String,
    pub git_rev: String,
    /// (I, N) of `--shard I/N`.
    pub shard: (usize, usize),
    /// Folder where studies save each point's image (`--save-images`), or none.
    pub save_images: Option<std::path::PathBuf>,
    /// Compute FLIP for image rows.
    pub flip: bool,
    /// Point keys that already have a row (a resumed run): not run again.
    pub done: std::collections::HashSet<String>,
    /// Asked between rows: `Some(signal)` stops the run after the row in flight.
    pub interrupted: Option<fn() -> Option<&'static str>>,
    /// Cells every row carries (the GPU's identity and the batch job: `manifest::row_cells`).
    pub row_cells: Vec<(schema::Col, String)>,
}

/// Expands every study of the suite into groups, in suite order (deterministic: the shard
/// assignment is group index mod N).
pub fn expand(studies: &[&dyn Study], suite: &Suite, software: bool) -> Result<Vec<Group>> {
    let mut groups = Vec::new();
    for (si, spec) in suite.studies.iter().enumerate() {
        let study = by_kind(studies, spec.kind).ok_or_else(|| {
            CoreError::Param(format!(
                "suite '{}' study {si}: no study of kind '{}' in this binary (known: {})",
                suite.name,
                spec.kind,
                studies
                    .iter()
                    .map(|s| s.kind().name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })?;
        let points = points(study, spec).map_err(|e| {
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
                    kind: spec.kind,
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

pub use crate::floors::FLOORS;

/// Rows per group: the floors plus the study's points.
pub fn rows_in(groups: &[Group]) -> usize {
    groups.iter().map(|g| g.points.len() + FLOORS.len()).sum()
}

/// How a run ended.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunOutcome {
    /// Rows written by this run (a resumed run's earlier rows excluded).
    pub written: usize,
    /// Points skipped because the run folder already had their rows (`--resume`).
    pub already_done: usize,
    /// The signal that stopped the run after the row in flight, if one did.
    pub interrupted: Option<&'static str>,
}

/// The timing plan of a suite on this adapter kind (`[timing]`, then `[software]`'s
/// overrides on a software adapter).
pub fn timing_plan(suite: &Suite, software: bool) -> Result<TimingPlan> {
    TimingPlan::from_spec(&suite.timing_for(software))
        .map_err(|e| CoreError::Param(format!("suite '{}' [timing]: {e}", suite.name)))
}

/// Runs the groups, sending every row to `sink`; points whose key is in `opts.done` are not
/// run again (their floors are re-measured, unwritten, as the yardstick of the rest). Stops
/// after the row in flight when `opts.interrupted` says so.
pub fn run(
    gpu: &Gpu,
    studies: &[&dyn Study],
    suite: &Suite,
    groups: &[Group],
    opts: &RunOptions,
    sink: &mut dyn Sink,
) -> Result<RunOutcome> {
    let software = gpu.facts.is_software;
    let plan = timing_plan(suite, software)?;
    let timing_rule = plan.describe();
    let mut out = RunOutcome::default();
    let stop_now = || opts.interrupted.and_then(|f| f());
    for group in groups {
        if let Some(sig) = stop_now() {
            out.interrupted = Some(sig);
            return Ok(out);
        }
        let key_of = |p: &PointSpec| group.point_key(&p.method, p.given());
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
                .set(cols::STUDY, group.kind)
                .set(cols::SHARD, opts.shard.0)
                .set(cols::SHARDS, opts.shard.1)
                .set(cols::POINT_KEY, group.point_key(method, params))
                .set(cols::ADAPTER, &f.name)
                .set(cols::BACKEND, &f.backend)
                .set(cols::DEVICE_TYPE, &f.device_type)
                .set(cols::DRIVER, &f.driver)
                .set(cols::DRIVER_INFO, &f.driver_info)
                .set(cols::ADAPTER_FEATURES, &f.features)
                .set(cols::TEXTURE_MEMORY, gpu.texture_memory.as_str())
                .set(cols::LIMITS, gpu.profile.name())
                .set(cols::WIDTH, group.width)
                .set(cols::HEIGHT, group.height)
                .set(cols::SCENE, &group.scene.generator)
                .set(cols::SCENE_LABEL, group.scene.label());
            if plan.interleave {
                row.set(cols::ORDER_SEED, plan.seed);
            }
            for (c, v) in opts.row_cells.iter().filter(|(_, v)| !v.is_empty()) {
                row.set(*c, v);
            }
            if row.get(cols::METHOD).is_none() {
                row.set(cols::METHOD, method);
            }
            // Every GPU frame is timed by `measure` under this plan; a row timed otherwise
            // (CPU-only work) says how in its own `timing_rule`.
            if row.get(cols::TIMING_RULE).is_none() {
                row.set(cols::TIMING_RULE, &timing_rule);
            }
            if row.status().is_none() {
                row.set_status(Status::Ok);
            }
            row
        };
        let floors: Vec<PointSpec> = FLOORS
            .iter()
            .map(|f| PointSpec {
                method: f.name().to_string(),
                point: Point::empty(),
            })
            .collect();
        // What this run still owes: the points (and floors) without a row yet.
        let todo: Vec<PointSpec> = group
            .points
            .iter()
            .filter(|p| !opts.done.contains(&key_of(p)))
            .cloned()
            .collect();
        let floors_todo: Vec<bool> = floors
            .iter()
            .map(|p| !opts.done.contains(&key_of(p)))
            .collect();
        let owed = todo.len() + floors_todo.iter().filter(|t| **t).count();
        out.already_done += group.points.len() + floors.len() - owed;
        if owed == 0 {
            continue;
        }
        let group = Group {
            points: todo,
            ..group.clone()
        };
        let group = &group;
        let write = |sink: &mut dyn Sink, row: &Row, out: &mut RunOutcome| -> Result<()> {
            sink.point_done(row)?;
            out.written += 1;
            Ok(())
        };
        let fail_all =
            |sink: &mut dyn Sink, out: &mut RunOutcome, why: &str, skipped: bool| -> Result<()> {
                let owed_floors = floors.iter().zip(&floors_todo).filter(|(_, t)| **t);
                for p in owed_floors.map(|(p, _)| p).chain(group.points.iter()) {
                    let mut row = Row::new();
                    set_params(&mut row, &p.point.recorded())?;
                    let row = if skipped {
                        skipped_row(row, why)
                    } else {
                        failed_row(row, why)
                    };
                    sink.point_done(&meta(row, &p.method, p.given()))?;
                    out.written += 1;
                }
                Ok(())
            };
        let scene: Scene = match group.scene.build() {
            Ok(s) => s,
            // Not fetched yet: what the adapter cannot run is skipped; this is what the checkout
            // lacks, and the reason says the command that fetches it.
            Err(e @ scenarios::SceneError::ModelMissing { .. }) => {
                fail_all(sink, &mut out, &format!("scene: {e}"), true)?;
                continue;
            }
            Err(e) => {
                fail_all(sink, &mut out, &format!("scene: {e}"), false)?;
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
                    fail_all(sink, &mut out, &why, true)?;
                    continue;
                }
            }
        }
        if let Err(e) = gpu.check_lost() {
            fail_all(sink, &mut out, &e.to_string(), false)?;
            continue;
        }
        let gscene = GpuScene::upload(gpu, &scene, group.width, group.height);
        let spec = &suite.studies[group.study_index];
        let mut ctx = GroupCtx::new(gpu, suite, spec, group, &scene, &gscene, plan.clone());
        ctx.images_dir = opts.save_images.clone();
        ctx.flip = opts.flip;
        let add_scene = |row: &mut Row| {
            row.set(cols::TRIANGLES, scene.mesh.triangle_count())
                .set(cols::VERTICES, scene.mesh.vertex_count());
        };
        // Floors first: they are every other row's yardstick (re-measured on a resumed run
        // whose floor rows exist, but not written again).
        for (f, owed) in FLOORS.iter().zip(&floors_todo) {
            let mut row = Row::new();
            row.set(cols::METHOD, f.name())
                .set(cols::CLAIMS_EXACT, false);
            add_scene(&mut row);
            let make = |s: &GpuScene| Ok::<_, CoreError>(Box::new(f.prepare(gpu, s)));
            let row = match measure_timed(gpu, &gscene, &make, &plan) {
                Ok(m) => {
                    set_timing(&mut row, &m, &scene.mesh);
                    match f {
                        Floor::Depth => ctx.floor_ms = m.gpu_median(),
                        Floor::BlendConst => ctx.blend_ms = m.gpu_median(),
                        _ => {}
                    }
                    row
                }
                Err(e) => error_row(row, &e),
            };
            if *owed {
                let mut row = meta(row, f.name(), &Params::new());
                set_x_floor(&mut row, ctx.floor_ms, ctx.blend_ms);
                write(sink, &row, &mut out)?;
            }
        }
        let study = by_kind(studies, group.kind).expect("checked in expand");
        let mut done = vec![false; group.points.len()];
        let mut sink_err: Option<CoreError> = None;
        let (floor_ms, blend_ms) = (ctx.floor_ms, ctx.blend_ms);
        let mut interrupted = None;
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
                out.written += 1;
                // A signal ends the run after the row in flight: the study stops here.
                if let Some(sig) = stop_now() {
                    interrupted = Some(sig);
                    return Err(CoreError::Interrupted(sig.to_string()));
                }
                Ok(())
            };
            study.run_group(&ctx, &mut emit)
        };
        if let Some(e) = sink_err {
            return Err(e);
        }
        if let Some(sig) = interrupted {
            // The points not emitted stay owed: `--resume` runs them.
            out.interrupted = Some(sig);
            return Ok(out);
        }
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
                set_params(&mut row, &p.point.recorded())?;
                add_scene(&mut row);
                write(
                    sink,
                    &meta(failed_row(row, &why), &p.method, p.given()),
                    &mut out,
                )?;
            }
        }
    }
    Ok(out)
}

/// `gpu_time_trusted`, and `x_floor` and `x_blend`: the row's median GPU time over the group's
/// floors, only where the timestamps cover the frame (a row flagged `timestamps_incomplete`
/// has a GPU time that is not the frame's, so no ratio of it is a result).
fn set_x_floor(row: &mut Row, floor_ms: Option<f64>, blend_ms: Option<f64>) {
    let Some(g) = row.get_f(cols::GPU_MS_MEDIAN) else {
        return;
    };
    if !row.is_ok() {
        return;
    }
    let trusted = crate::record::gpu_time_trusted(row);
    row.set_bool(cols::GPU_TIME_TRUSTED, trusted);
    if !trusted {
        return;
    }
    for (col, floor) in [(cols::X_FLOOR, floor_ms), (cols::X_BLEND, blend_ms)] {
        if let Some(f) = floor.filter(|f| *f > 0.0) {
            row.set_f(col, g / f);
        }
    }
}

/// The commit mfx was built from (embedded at build time; never asked of the current directory).
pub fn git_rev() -> String {
    crate::build_info::git_rev()
}

/// Parses, checks and runs a suite's text on `gpu`, unsharded, and returns every row (tests and
/// tools). A suite with problems is an error listing them all; the row count is checked.
pub fn run_suite(gpu: &Gpu, studies: &[&dyn Study], text: &str, source: &str) -> Result<Vec<Row>> {
    let suite = Suite::parse(text, source)?;
    let problems = crate::check::check_suite(studies, &suite);
    if !problems.is_empty() {
        return Err(CoreError::Param(scenarios::problem::report(&problems)));
    }
    run_checked(gpu, studies, &suite)
}

/// Runs a checked suite on `gpu`, unsharded, into memory.
pub fn run_checked(gpu: &Gpu, studies: &[&dyn Study], suite: &Suite) -> Result<Vec<Row>> {
    let groups = expand(studies, suite, gpu.facts.is_software)?;
    let mut sink = crate::record::VecSink::default();
    let opts = RunOptions {
        run_id: "test".into(),
        git_rev: crate::build_info::git_rev(),
        shard: (0, 1),
        flip: true,
        ..Default::default()
    };
    let written = run(gpu, studies, suite, &groups, &opts, &mut sink)?.written;
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
pub fn rows_of(studies: &[&dyn Study], suite: &Suite, software: bool) -> usize {
    expand(studies, suite, software)
        .map(|g| rows_in(&g))
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::Flag;

    #[test]
    fn a_row_whose_timestamps_missed_work_gets_no_ratio_to_the_floors() {
        // lavapipe's compute A-buffer: GPU 3.45 ms for 255 ms of wall time.
        let mut row = Row::new();
        row.set_status(Status::Ok).set_f(cols::GPU_MS_MEDIAN, 3.45);
        let mut untrusted = row.clone();
        untrusted.add_flag(Flag::TimestampsIncomplete);
        set_x_floor(&mut untrusted, Some(10.0), Some(5.0));
        assert_eq!(untrusted.get_bool(cols::GPU_TIME_TRUSTED), Some(false));
        assert_eq!(untrusted.get(cols::X_FLOOR), None);
        assert_eq!(untrusted.get(cols::X_BLEND), None);
        set_x_floor(&mut row, Some(10.0), Some(5.0));
        assert_eq!(row.get_bool(cols::GPU_TIME_TRUSTED), Some(true));
        assert_eq!(row.get_f(cols::X_FLOOR), Some(3.45 / 10.0));
        assert_eq!(row.get_f(cols::X_BLEND), Some(3.45 / 5.0));
    }
}
