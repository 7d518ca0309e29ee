//! The `views` study (issue 42): the methods study's points, each rendered along its scene's
//! camera path (`scenarios::path`: an orbit, a fly-through, keyframes or a glTF camera
//! animation, or one view at rest) and judged view by view against that view's exact truth. One
//! row per method × scene × path (a point of a group whose scene carries the path), with:
//!
//! - the GPU time of every view (timed as any point is, by the suite's `[timing]`), summarised
//!   over the path: `gpu_ms_median` is the median of the views' medians, beside the p99 and the
//!   worst view (`gpu_ms_path_p99`, `gpu_ms_path_worst`, `gpu_ms_worst_view`);
//! - the judge's error of every view (`rmse`, `flip_mean`: means over the views; `exact`: every
//!   view exact) and its worst view (`rmse_path_worst`, `flip_path_worst`, …);
//! - flicker and popping between consecutive views and, at rest, the share of pixels that differ
//!   between repeated frames (`crate::temporal`);
//! - every view's numbers as JSON arrays in `path_series`, for the report's charts along the path;
//! - with `--save-images`, crops of the worst view (method, truth, FLIP map) and of the step where
//!   the row pops most (method and truth before and after, the popped pixels), in `views/`.
//!
//! Each view is a fresh preparation on a scene seen by that view's camera (a method may size its
//! buffers or derive constants from the camera in `prepare`, as `compute_abuffer`'s count does),
//! so every view's time is the time of a frame prepared for that view; the f64 reference of a
//! view is computed once per group (scene × resolution) and shared by every method, and a view
//! that repeats the previous one (at rest) reuses it. A view's captures are judged in parallel on
//! the CPU once every method has drawn it: the judge, not the GPU, is what a path costs.

use std::sync::Arc;

use rayon::prelude::*;
use scenarios::path::CameraPath;
use scenarios::{Camera, ParamValue, Scene, StudySpec};

use super::methods::{ready_points, set_reference_columns, GroupTruth, MethodsStudy, Ready};
use crate::aa::AaMode;
use crate::effects::EffectConfig;
use crate::judge::{self, JudgeError, Judgement, TruthCache};
use crate::method::{measure, Capture, Expected};
use bench_core::axes::{Axis, Point};
use bench_core::record::{cols, failed_row, Flag, FlagSet, Row};
use bench_core::study::InvalidPoint;
use bench_core::study::{Emit, GroupCtx, Methods, Opt, Study, StudyKind};
use bench_core::Result;
use mfx_reference::temporal::{self, Frame, Step};
use mfx_reference::{rasterize, FragmentLists};

pub struct ViewsStudy;

const POP_EPSILON: Opt = Opt {
    name: "pop_epsilon",
    doc: "ε of popping: a pixel pops when its error against the truth changes by more than this between consecutive views",
    kind: scenarios::ValueKind::Float {
        default: temporal::POP_EPSILON,
        min: 1e-6,
        max: 1.0,
    },
};
const FLIP: Opt = Opt {
    name: "flip",
    doc: "FLIP of every view (false: RMSE only, and the worst view is the worst by RMSE)",
    kind: scenarios::ValueKind::Bool { default: true },
};

/// Side of the crops saved with `--save-images` (pixels; the whole image when smaller).
const CROP: u32 = 192;

impl Study for ViewsStudy {
    fn kind(&self) -> StudyKind {
        StudyKind::Views
    }
    fn describe(&self) -> &'static str {
        "multi-fragment methods along a camera path: time, error, flicker and popping per view vs each view's exact truth"
    }
    fn methods(&self) -> Methods {
        MethodsStudy.methods()
    }
    fn axes(&self, method: &str) -> Vec<Axis> {
        MethodsStudy.axes(method)
    }
    fn validate(&self, method: &str, point: &Point) -> std::result::Result<(), InvalidPoint> {
        MethodsStudy.validate(method, point)
    }
    fn options(&self) -> Vec<Opt> {
        vec![POP_EPSILON, FLIP]
    }
    fn moves_camera(&self) -> bool {
        true
    }
    fn check_table(&self, spec: &StudySpec) -> Vec<String> {
        spec.scenes
            .iter()
            .zip(&spec.scene_tables)
            .filter(|(s, _)| !matches!(CameraPath::of(s), Ok(Some(_)) | Err(_)))
            .map(|(s, j)| {
                format!(
                    "scene {j} ({}) has no camera_path: the views study renders a path (orbit, fly, file or at_rest)",
                    s.generator
                )
            })
            .collect()
    }
    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
        run_views_group(ctx, emit)
    }
}

fn pop_epsilon(spec: &StudySpec) -> f64 {
    match POP_EPSILON.value(spec) {
        Some(ParamValue::Float(x)) => x,
        _ => temporal::POP_EPSILON,
    }
}

/// One view's truth, shared by every method of the group at that view.
struct View {
    camera: Camera,
    lists: FragmentLists,
    /// Per pixel, the f32 bound of an exact composite ([`judge::exact_bounds`]' `arith`).
    bounds: Arc<Vec<f64>>,
    truths: TruthCache,
}

/// One view of one row, as `path_series` lists it.
#[derive(Clone, Debug, Default)]
struct ViewRecord {
    gpu_ms: Option<f64>,
    rmse: Option<f64>,
    flip: Option<f64>,
    exact: Option<bool>,
    /// From the previous view (None at view 0).
    step: Option<Step>,
}

/// The previous view of a row: what the next step is measured from.
struct Prev {
    image: Vec<[f32; 4]>,
    truth: Arc<Vec<[f64; 4]>>,
    bound: Option<Arc<Vec<f64>>>,
}

/// Crops (RGB8, `w` × `h`) of a row's worst view: method, truth, FLIP map (when FLIP ran).
#[derive(Clone, Debug)]
struct Crops {
    view: usize,
    w: u32,
    h: u32,
    images: Vec<(&'static str, Vec<u8>)>,
}

/// What judging one capture at one view gave.
struct Outcome {
    judgement: Judgement,
    image: Vec<[f32; 4]>,
    truth: Arc<Vec<[f64; 4]>>,
    bound: Option<Arc<Vec<f64>>>,
    step: Option<Step>,
    worst: Option<Crops>,
    strip: Option<Crops>,
    judge_ms: f64,
}

/// A row along its path.
struct PathRow {
    ready: Ready,
    /// Set when a view could not be measured or judged: the row emitted instead.
    failed: Option<Row>,
    views: Vec<ViewRecord>,
    prev: Option<Prev>,
    flags: FlagSet,
    notes: Vec<String>,
    bytes_max: u64,
    samples: usize,
    cpu_ms: Vec<f64>,
    measure_ms: f64,
    prepare_ms: f64,
    judge_ms: f64,
    max_abs: f64,
    bad_frac: Vec<f64>,
    overflow: f64,
    hazard: Option<f64>,
    collision: Option<f64>,
    worst: Option<Crops>,
    strip: Option<Crops>,
}

impl PathRow {
    fn new(ready: Ready) -> PathRow {
        PathRow {
            ready,
            failed: None,
            views: Vec::new(),
            prev: None,
            flags: FlagSet::default(),
            notes: Vec::new(),
            bytes_max: 0,
            samples: 0,
            cpu_ms: Vec::new(),
            measure_ms: 0.0,
            prepare_ms: 0.0,
            judge_ms: 0.0,
            max_abs: 0.0,
            bad_frac: Vec::new(),
            overflow: 0.0,
            hazard: None,
            collision: None,
            worst: None,
            strip: None,
        }
    }

    fn fail(&mut self, v: usize, why: &str) {
        let row = std::mem::take(&mut self.ready.row);
        self.failed = Some(failed_row(row, &format!("view {v}: {why}")));
    }

    /// The worst view's score so far (FLIP mean, else RMSE).
    fn worst_score(&self, flip: bool) -> f64 {
        self.views
            .iter()
            .filter_map(|r| if flip { r.flip } else { r.rmse })
            .fold(0.0, f64::max)
    }

    fn worst_popping(&self) -> f64 {
        self.views
            .iter()
            .filter_map(|r| r.step.map(|s| s.popping))
            .fold(0.0, f64::max)
    }
}

/// Runs every point of a views group along the scene's camera path; one row per point.
pub fn run_views_group(ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
    let cameras = ctx.scene.views.clone();
    let truth = GroupTruth::new(ctx);
    let ready = ready_points(ctx, &truth, emit, &|_, _, _| {})?;
    let Some(path) = ctx.scene.path.filter(|_| !cameras.is_empty()) else {
        for r in ready {
            let why = "the scene has no camera_path: the views study renders a path";
            emit(r.index, failed_row(r.row, why))?;
        }
        return Ok(());
    };
    let eps = pop_epsilon(ctx.study);
    let flip = FLIP.bool(ctx.study) && ctx.flip;
    let images = ctx.images_dir.is_some();
    let (w, h) = (ctx.group.width, ctx.group.height);
    let mut rows: Vec<PathRow> = ready.into_iter().map(PathRow::new).collect();
    let mut scene = ctx.scene.clone();
    let mut view: Option<Arc<View>> = None;
    let mut reference_ms = 0.0;
    // The next view's reference (its fragment lists and the truths this view's judging asked
    // for) is made on the CPU while the GPU draws this view: on a 1024² path the truths, not the
    // GPU, are most of a path's wall time. One core is left to the thread that drives the GPU.
    let cores = rayon::current_num_threads().saturating_sub(1).max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(cores)
        .build()
        .map_err(|e| {
            bench_core::CoreError::Io(format!("the views study's reference threads: {e}"))
        })?;
    let mut wants: Vec<Want> = Vec::new();
    let mut next: Option<(View, f64)> = None;
    for (v, cam) in cameras.iter().enumerate() {
        if view.as_ref().is_none_or(|x| x.camera != *cam) {
            scene.camera = cam.clone();
            let (made, ms) = match next.take() {
                Some(n) if n.0.camera == *cam => n,
                _ => make_view(&scene, w, h, &[]),
            };
            reference_ms += ms;
            view = Some(Arc::new(made));
        }
        let after = cameras.get(v + 1).filter(|c| **c != *cam).cloned();
        let mut ahead = after.map(|c| {
            let mut s = scene.clone();
            s.camera = c;
            s
        });
        let vw = view.clone().expect("set above");
        let (done, judged) = std::thread::scope(|s| {
            let handle = ahead.as_mut().map(|sc| {
                let (sc, wants, pool) = (&*sc, &wants, &pool);
                s.spawn(move || pool.install(|| make_view(sc, w, h, wants)))
            });
            let judged = draw_and_judge(ctx, &mut rows, &vw, &scene, v, cam, flip, eps, images);
            (handle.map(|h| h.join()), judged)
        });
        next = match done {
            Some(Ok(n)) => Some(n),
            // A panic in the reference is the same panic as when it ran on this thread.
            Some(Err(p)) => std::panic::resume_unwind(p),
            None => None,
        };
        wants = judged.wants;
        for (i, o) in judged.outcomes {
            let r = &mut rows[i];
            match o {
                Ok(o) => apply(r, o),
                Err(why) => r.fail(v, &why.to_string()),
            }
        }
    }
    let mut first = true;
    for r in rows {
        let index = r.ready.index;
        let row = match r.failed {
            Some(row) => row,
            None => finish(
                ctx,
                path,
                r,
                eps,
                first.then_some(reference_ms),
                view.as_deref(),
            )?,
        };
        first = false;
        emit(index, row)?;
    }
    Ok(())
}

/// A view's reference, made before the view is judged: its fragment lists, their f32 bounds,
/// and the truths of `wants`; with the milliseconds the lists and bounds took (`reference_ms`).
fn make_view(scene: &Scene, w: u32, h: u32, wants: &[Want]) -> (View, f64) {
    let t = std::time::Instant::now();
    let lists = rasterize(scene, w, h);
    let bounds = judge::exact_bounds(&lists.depth_complexity(), None)
        .iter()
        .map(|b| b.arith)
        .collect();
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let view = View {
        camera: scene.camera.clone(),
        lists,
        bounds: Arc::new(bounds),
        truths: TruthCache::default(),
    };
    for want in wants {
        match *want {
            Want::Effect(e) => {
                view.truths.get(&e, Expected::All, || {
                    e.reference(scene, &view.lists, Expected::All)
                });
            }
            // Kept by the antialiasing truths' own cache, where the judge looks first.
            Want::Aa(mode, e, expected) => {
                crate::aa::truth_cached(scene, w, h, mode, &e, Expected::All);
                if expected != Expected::All {
                    crate::aa::truth_cached(scene, w, h, mode, &e, expected);
                }
            }
        }
    }
    (view, ms)
}

/// A truth a view's judging asked for: a single-sample effect's, or an antialiased one's.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Want {
    Effect(EffectConfig),
    Aa(AaMode, EffectConfig, Expected),
}

/// One view drawn by every live row and judged.
struct Judged {
    outcomes: Vec<(usize, std::result::Result<Outcome, JudgeError>)>,
    /// The truths the judging asked for, for the next view's [`make_view`].
    wants: Vec<Want>,
}

/// View `v`: every live row draws it on the GPU, one after another (time, readback, the
/// method's own judge), then every capture is judged against the view's truth at once.
#[allow(
    clippy::too_many_arguments,
    reason = "one view of a path: the group, its rows, the view and the judge's settings"
)]
fn draw_and_judge(
    ctx: &GroupCtx<'_>,
    rows: &mut [PathRow],
    vw: &View,
    scene: &Scene,
    v: usize,
    cam: &Camera,
    flip: bool,
    eps: f64,
    images: bool,
) -> Judged {
    let gscene = ctx.gscene.with_camera(ctx.gpu, cam);
    // The GPU: every live row draws this view, one after another.
    let mut caps: Vec<(usize, Capture)> = Vec::new();
    for (i, r) in rows.iter_mut().enumerate() {
        if r.failed.is_some() {
            continue;
        }
        let pt = &ctx.group.points[r.ready.index];
        let mut m = match measure(
            ctx.gpu,
            &gscene,
            r.ready.method.as_ref(),
            &pt.point,
            &ctx.plan,
        ) {
            Ok(m) => m,
            Err(e) => {
                r.fail(v, &e.to_string());
                continue;
            }
        };
        let g = m.gpu_median();
        if let Some(g) = g {
            if bench_core::measure::timestamps_incomplete(g, m.cpu.median) {
                r.flags.add(Flag::TimestampsIncomplete);
            }
        }
        if !m.target_reached {
            r.flags.add(Flag::Noisy);
        }
        r.bytes_max = r.bytes_max.max(m.bytes_allocated);
        r.samples += m.samples.len() - m.discarded();
        r.cpu_ms.push(m.cpu.median);
        r.measure_ms += m.measure_ms;
        r.prepare_ms += m.prepare_ms;
        r.views.push(ViewRecord {
            gpu_ms: g,
            ..Default::default()
        });
        let mut cap = match m.prepared.readback(ctx.gpu, &gscene) {
            Ok(c) => c,
            Err(e) => {
                r.fail(v, &format!("readback: {e}"));
                continue;
            }
        };
        // The method's own judge (hazards, its CPU twin) sees this view's fragments.
        m.prepared.judge(&mut cap, &vw.lists);
        caps.push((i, cap));
    }
    // The truth of every effect a row needs, composited once before the rows share it.
    for (i, cap) in &caps {
        if cap.aa.is_none() {
            let e = rows[*i].ready.effect;
            vw.truths.get(&e, Expected::All, || {
                e.reference(scene, &vw.lists, Expected::All)
            });
        }
    }
    // What the next view's judging will ask for, made ahead while the GPU draws it.
    let mut wants: Vec<Want> = Vec::new();
    for (i, cap) in &caps {
        let effect = rows[*i].ready.effect;
        let want = match crate::aa::antialiased(cap) {
            None => Want::Effect(effect),
            Some(mode) => Want::Aa(mode, effect, cap.expected),
        };
        if !wants.contains(&want) {
            wants.push(want);
        }
    }
    // The CPU: every capture of this view judged at once.
    let outcomes: Vec<(usize, std::result::Result<Outcome, JudgeError>)> = caps
        .into_par_iter()
        .map(|(i, cap)| {
            (
                i,
                judge_view(&rows[i], cap, vw, scene, v, flip, eps, images),
            )
        })
        .collect();
    Judged { outcomes, wants }
}

/// Judges one capture of view `v`: the judge's verdict, the step from the row's previous view,
/// and (with images) crops where this view is the row's worst or its largest pop so far.
#[allow(
    clippy::too_many_arguments,
    reason = "one view judged: its row, capture, view, scene and the judge's settings"
)]
fn judge_view(
    r: &PathRow,
    cap: Capture,
    vw: &View,
    scene: &Scene,
    v: usize,
    flip: bool,
    eps: f64,
    images: bool,
) -> std::result::Result<Outcome, JudgeError> {
    let t = std::time::Instant::now();
    let effect = r.ready.effect;
    let cx = judge::Context {
        scene,
        effect: &effect,
        exact: r.ready.method.exact(),
        flip,
        truths: Some(&vw.truths),
    };
    let judgement = judge::judge(&cap, &vw.lists, cx)?;
    let (truth, bound) = match crate::aa::reference_for(&cap, scene, &vw.lists, &effect) {
        Some(a) => (Arc::new(a.truth), None),
        None => (
            vw.truths.get(&effect, Expected::All, || {
                effect.reference(scene, &vw.lists, Expected::All)
            }),
            Some(vw.bounds.clone()),
        ),
    };
    let image = cap.image.ok_or(JudgeError::NoImage)?;
    let frame = Frame {
        image: &image,
        truth: &truth,
        bound: bound.as_deref().map(Vec::as_slice),
    };
    let prev = r.prev.as_ref().map(|p| Frame {
        image: &p.image,
        truth: &p.truth,
        bound: p.bound.as_deref().map(Vec::as_slice),
    });
    let step = prev.as_ref().map(|p| temporal::step(p, &frame, eps));
    let (w, h) = (vw.lists.width, vw.lists.height);
    let score = if flip {
        judgement.flip.as_ref().map(|f| f.result.mean)
    } else {
        judgement.truth.map(|e| e.rmse)
    };
    let worst = match score {
        Some(s) if images && s > r.worst_score(flip) => {
            Some(worst_crops(&judgement, &frame, w, h, v))
        }
        _ => None,
    };
    let strip = match (&prev, step) {
        (Some(p), Some(s)) if images && s.popping > r.worst_popping() => {
            Some(strip_crops(p, &frame, eps, w, h, v))
        }
        _ => None,
    };
    Ok(Outcome {
        judgement,
        image,
        truth,
        bound,
        step,
        worst,
        strip,
        judge_ms: t.elapsed().as_secs_f64() * 1e3,
    })
}

fn apply(r: &mut PathRow, o: Outcome) {
    let j = &o.judgement;
    let rec = r.views.last_mut().expect("pushed when measured");
    rec.rmse = j.truth.map(|e| e.rmse);
    rec.flip = j.flip.as_ref().map(|f| f.result.mean);
    rec.exact = j.exact;
    rec.step = o.step;
    if let Some(e) = j.truth {
        r.max_abs = r.max_abs.max(e.max_abs);
        r.bad_frac.push(e.bad_pixel_frac);
    }
    r.overflow = r.overflow.max(j.overflow_rate);
    if let Some(x) = j.hazard_rate {
        r.hazard = Some(r.hazard.unwrap_or(0.0).max(x));
    }
    if let Some(x) = j.collision_rate {
        r.collision = Some(r.collision.unwrap_or(0.0).max(x));
    }
    r.flags.add_all(&j.flags);
    for n in &j.notes {
        if !r.notes.contains(n) && r.notes.len() < 4 {
            r.notes.push(n.clone());
        }
    }
    r.judge_ms += o.judge_ms;
    if o.worst.is_some() {
        r.worst = o.worst;
    }
    if o.strip.is_some() {
        r.strip = o.strip;
    }
    r.prev = Some(Prev {
        image: o.image,
        truth: o.truth,
        bound: o.bound,
    });
}

/// The row of a path that ran to its end.
fn finish(
    ctx: &GroupCtx<'_>,
    path: &str,
    r: PathRow,
    eps: f64,
    reference_ms: Option<f64>,
    last: Option<&View>,
) -> Result<Row> {
    let mut row = r.ready.row;
    let pick = |f: &dyn Fn(&ViewRecord) -> Option<f64>| -> Vec<f64> {
        r.views.iter().map(|v| f(v).unwrap_or(f64::NAN)).collect()
    };
    let gpu = pick(&|v| v.gpu_ms);
    let rmse = pick(&|v| v.rmse);
    let flip = pick(&|v| v.flip);
    // Steps are indexed by the view they arrive at (view 0 has none).
    let flicker = pick(&|v| v.step.map(|s| s.flicker));
    let popping = pick(&|v| v.step.map(|s| s.popping));
    let changed = pick(&|v| v.step.map(|s| s.changed));
    row.set(cols::CAMERA_PATH, path)
        .set(cols::PATH_VIEWS, r.views.len())
        .set_f(cols::POP_EPSILON, eps);
    if let Some(t) = temporal::over_path(&gpu) {
        row.set_f(cols::GPU_MS_MEDIAN, t.median)
            .set_f(
                cols::GPU_MS_MIN,
                gpu.iter()
                    .copied()
                    .filter(|x| x.is_finite())
                    .fold(f64::INFINITY, f64::min),
            )
            .set_f(cols::GPU_MS_MAX, t.worst)
            .set_f(cols::GPU_MS_PATH_P99, t.p99)
            .set_f(cols::GPU_MS_PATH_WORST, t.worst)
            .set(cols::GPU_MS_WORST_VIEW, t.worst_view);
    }
    if let Some(c) = temporal::over_path(&r.cpu_ms) {
        row.set_f(cols::CPU_MS_MEDIAN, c.median);
    }
    row.set(cols::SAMPLES, r.samples)
        .set_f(cols::MEASURE_MS, r.measure_ms)
        .set_f(cols::PREPARE_MS, r.prepare_ms)
        .set_f(cols::JUDGE_MS, r.judge_ms)
        .set(cols::BYTES_ALLOCATED, r.bytes_max)
        .set_f(
            cols::BYTES_PER_PIXEL,
            r.bytes_max as f64 / (ctx.group.width as f64 * ctx.group.height as f64),
        );
    if let Some(ms) = reference_ms {
        row.set_f(cols::FRAGMENT_REFERENCE_MS, ms);
    }
    if let Some(last) = last {
        set_reference_columns(&mut row, &last.lists);
    }
    if let Some(e) = temporal::over_path(&rmse) {
        row.set_f(cols::RMSE, e.mean)
            .set_f(cols::RMSE_PATH_WORST, e.worst)
            .set(cols::RMSE_WORST_VIEW, e.worst_view)
            .set_f(cols::MAX_ABS_ERR, r.max_abs);
    }
    if !r.bad_frac.is_empty() {
        row.set_f(
            cols::BAD_PIXEL_FRAC,
            r.bad_frac.iter().sum::<f64>() / r.bad_frac.len() as f64,
        )
        .set_f(cols::BAD_PIXEL_TOL, mfx_reference::metrics::BAD_PIXEL_TOL);
    }
    if let Some(f) = temporal::over_path(&flip) {
        row.set_f(cols::FLIP_MEAN, f.mean)
            .set_f(cols::FLIP_PATH_WORST, f.worst)
            .set(cols::FLIP_WORST_VIEW, f.worst_view);
    }
    let exact: Vec<bool> = r.views.iter().filter_map(|v| v.exact).collect();
    if exact.len() == r.views.len() {
        row.set(cols::EXACT, exact.iter().all(|e| *e))
            .set(cols::VIEWS_EXACT, exact.iter().filter(|e| **e).count());
    }
    row.set_f(cols::OVERFLOW_RATE, r.overflow);
    if let Some(x) = r.hazard {
        row.set_f(cols::HAZARD_RATE, x);
    }
    if let Some(x) = r.collision {
        row.set_f(cols::COLLISION_RATE, x);
    }
    if let Some(f) = temporal::over_path(&flicker) {
        row.set_f(cols::FLICKER_MEAN, f.mean)
            .set_f(cols::FLICKER_MAX, f.worst);
        // No worst view where no step flickered (every view would be "the worst").
        if f.worst > 0.0 {
            row.set(cols::FLICKER_WORST_VIEW, f.worst_view);
        }
    }
    let steps: Vec<Step> = r.views.iter().filter_map(|v| v.step).collect();
    let bounds: Vec<f64> = steps.iter().filter_map(|s| s.flicker_bound).collect();
    if !bounds.is_empty() && bounds.len() == steps.len() {
        row.set_f(
            cols::FLICKER_BOUND_MEAN,
            bounds.iter().sum::<f64>() / bounds.len() as f64,
        )
        .set(
            cols::FLICKER_BEYOND_BOUND,
            steps.iter().filter_map(|s| s.beyond_bound).sum::<usize>(),
        );
    }
    if let Some(p) = temporal::over_path(&popping) {
        row.set_f(cols::POPPING_MEAN, p.mean)
            .set_f(cols::POPPING_MAX, p.worst);
        if p.worst > 0.0 {
            row.set(cols::POPPING_WORST_VIEW, p.worst_view);
        }
    }
    // Every view the same camera: the changed pixels are the at-rest measure.
    if path == scenarios::path::AT_REST {
        if let Some(c) = temporal::over_path(&changed) {
            row.set_f(cols::AT_REST_CHANGED_MEAN, c.mean)
                .set_f(cols::AT_REST_CHANGED_MAX, c.worst);
        }
    }
    let series = serde_json::json!({
        "gpu_ms": gpu.iter().map(|x| x.is_finite().then_some(*x)).collect::<Vec<_>>(),
        "rmse": rmse.iter().map(|x| x.is_finite().then_some(*x)).collect::<Vec<_>>(),
        "flip": flip.iter().map(|x| x.is_finite().then_some(*x)).collect::<Vec<_>>(),
        "flicker": flicker.iter().map(|x| x.is_finite().then_some(*x)).collect::<Vec<_>>(),
        "popping": popping.iter().map(|x| x.is_finite().then_some(*x)).collect::<Vec<_>>(),
        "changed": changed.iter().map(|x| x.is_finite().then_some(*x)).collect::<Vec<_>>(),
        "exact": r.views.iter().map(|v| v.exact).collect::<Vec<_>>(),
    });
    row.set(cols::PATH_SERIES, series.to_string());
    row.add_flags(&r.flags);
    for n in &r.notes {
        row.add_note(n);
    }
    if let (Some(dir), true) = (&ctx.images_dir, r.worst.is_some() || r.strip.is_some()) {
        let pt = &ctx.group.points[r.ready.index];
        let key = ctx.group.point_key(&pt.method, pt.given());
        let f = &ctx.gpu.facts;
        let prefix = format!(
            "views/{}",
            bench_core::image_io::point_hash(&key, &f.name, &f.backend)
        );
        std::fs::create_dir_all(dir.join("views"))
            .map_err(|e| bench_core::CoreError::Io(format!("{}: {e}", dir.display())))?;
        for (tag, c) in [("worst", &r.worst), ("pop", &r.strip)] {
            let Some(c) = c else { continue };
            for (name, rgb8) in &c.images {
                let p = dir.join(format!("{prefix}-{tag}-{name}.png"));
                mfx_flip::save_rgb8_png(&p, rgb8, c.w, c.h)
                    .map_err(|e| bench_core::CoreError::Io(e.to_string()))?;
            }
        }
        row.set(cols::PATH_IMAGES, &prefix);
        if let Some(c) = &r.worst {
            row.set(cols::PATH_IMAGES_WORST_VIEW, c.view);
        }
        if let Some(c) = &r.strip {
            row.set(cols::PATH_IMAGES_POP_VIEW, c.view);
        }
    }
    Ok(row)
}

/// The `side` × `side` window (clamped to the image) with the largest sum of `weight`, by a
/// summed-area table: (x0, y0, w, h).
fn window(weight: &dyn Fn(usize) -> f64, w: u32, h: u32, side: u32) -> (u32, u32, u32, u32) {
    let (cw, ch) = (side.min(w), side.min(h));
    let (wu, hu) = (w as usize, h as usize);
    let mut sat = vec![0.0f64; (wu + 1) * (hu + 1)];
    for y in 0..hu {
        let mut run = 0.0;
        for x in 0..wu {
            run += weight(y * wu + x);
            sat[(y + 1) * (wu + 1) + x + 1] = sat[y * (wu + 1) + x + 1] + run;
        }
    }
    let at = |x: usize, y: usize| sat[y * (wu + 1) + x];
    let (mut best, mut pos) = (f64::NEG_INFINITY, (0, 0));
    for y in 0..=(hu - ch as usize) {
        for x in 0..=(wu - cw as usize) {
            let (x1, y1) = (x + cw as usize, y + ch as usize);
            let s = at(x1, y1) - at(x, y1) - at(x1, y) + at(x, y);
            if s > best {
                best = s;
                pos = (x, y);
            }
        }
    }
    (pos.0 as u32, pos.1 as u32, cw, ch)
}

/// The RGB8 pixels of `win` from a `w`-wide RGB8 image.
fn crop(rgb8: &[u8], w: u32, win: (u32, u32, u32, u32)) -> Vec<u8> {
    let (x0, y0, cw, ch) = win;
    let mut out = Vec::with_capacity((cw * ch * 3) as usize);
    for y in y0..y0 + ch {
        let start = ((y * w + x0) * 3) as usize;
        out.extend_from_slice(&rgb8[start..start + (cw * 3) as usize]);
    }
    out
}

fn over_white(img: &[[f32; 4]], px: usize) -> Vec<u8> {
    mfx_flip::composite_srgb8(&img[..px], [1.0; 3])
}

fn truth_over_white(truth: &[[f64; 4]], px: usize) -> Vec<u8> {
    let t: Vec<[f32; 4]> = truth[..px].iter().map(|p| p.map(|c| c as f32)).collect();
    over_white(&t, px)
}

/// Crops of a worst view around its largest error (the FLIP map, else the per-pixel error).
fn worst_crops(j: &Judgement, f: &Frame<'_>, w: u32, h: u32, view: usize) -> Crops {
    let px = (w * h) as usize;
    let err = |i: usize| {
        (0..4)
            .map(|c| (f.image[i][c] as f64 - f.truth[i][c]).abs())
            .fold(0.0, f64::max)
    };
    let win = match &j.flip {
        Some(fl) => window(&|i| fl.result.map[i] as f64, w, h, CROP),
        None => window(
            &|i| if err(i).is_finite() { err(i) } else { 1.0 },
            w,
            h,
            CROP,
        ),
    };
    let mut images = vec![
        ("method", crop(&over_white(f.image, px), w, win)),
        ("truth", crop(&truth_over_white(f.truth, px), w, win)),
    ];
    if let Some(fl) = &j.flip {
        images.push((
            "flip",
            crop(&mfx_flip::magma_rgb8(&fl.result.map[..px]), w, win),
        ));
    }
    Crops {
        view,
        w: win.2,
        h: win.3,
        images,
    }
}

/// A frame strip of a pop: method and truth before and after, and the popped pixels (white),
/// around the most popped pixels.
fn strip_crops(prev: &Frame<'_>, cur: &Frame<'_>, eps: f64, w: u32, h: u32, view: usize) -> Crops {
    let px = (w * h) as usize;
    let mut mask = vec![0u8; px];
    for i in temporal::popped_pixels(prev, cur, eps) {
        mask[i % px] = 1;
    }
    let win = window(&|i| mask[i] as f64, w, h, CROP);
    let mask_rgb8: Vec<u8> = mask.iter().flat_map(|&m| [m * 255; 3]).collect();
    Crops {
        view,
        w: win.2,
        h: win.3,
        images: vec![
            ("method-before", crop(&over_white(prev.image, px), w, win)),
            ("method-after", crop(&over_white(cur.image, px), w, win)),
            (
                "truth-before",
                crop(&truth_over_white(prev.truth, px), w, win),
            ),
            (
                "truth-after",
                crop(&truth_over_white(cur.truth, px), w, win),
            ),
            ("popped", crop(&mask_rgb8, w, win)),
        ],
    }
}
