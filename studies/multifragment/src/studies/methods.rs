//! The `methods` study: every multi-fragment method on every scene, timed, and judged against
//! the exact CPU reference; `speedup_vs_depth_peel` comes from depth_peel in the same group.

use std::cell::OnceCell;

use crate::effects::{self, EffectConfig};
use crate::judge::{self, TruthCache};
use crate::method::{measure, measure_interleaved, Method, Prepared};
use crate::methods::{self};
use bench_core::axes::{Axis, Point};
use bench_core::measure::set_timing;
use bench_core::record::cols;
use bench_core::record::{error_row, failed_row, set_params, skipped_row};
use bench_core::record::{Flag, Row};
use bench_core::study::InvalidPoint;
use bench_core::study::{Emit, GroupCtx, Methods, PointSpec, Study, StudyKind};
use bench_core::Result;
use mfx_reference::{rasterize, FragmentLists};

pub struct MethodsStudy;

/// The method every other row's `speedup_vs_depth_peel` is read against (run first).
pub const BASELINE: &str = "depth_peel";

/// Whether `m` folds every effect (declares the effects fold's axes).
fn folds_effects(m: &dyn Method) -> bool {
    let axes = m.axes();
    effects::AXES
        .iter()
        .all(|e| axes.iter().any(|a| a.name() == e.name()))
}

/// The effect of a point: read through the fold's axes when the method folds effects; for one
/// that does not, only the effect's name (its other axes are not the method's).
fn effect_of(m: &dyn Method, point: &Point) -> std::result::Result<EffectConfig, InvalidPoint> {
    if folds_effects(m) {
        return EffectConfig::from_point(point);
    }
    let effect = effects::Effect::parse(&point.choice(&effects::EFFECT))?;
    Ok(EffectConfig {
        effect,
        ..Default::default()
    })
}

impl Study for MethodsStudy {
    fn kind(&self) -> StudyKind {
        StudyKind::Methods
    }
    fn describe(&self) -> &'static str {
        "multi-fragment capture methods: time, memory, and error vs the exact CPU reference"
    }
    fn methods(&self) -> Methods {
        Methods::List(methods::all().iter().map(|m| m.name()).collect())
    }
    /// The method's axes; the effect axis is expanded for every method: one that folds no
    /// effects gets a `skipped` row for each effect but transparency, never a silent gap.
    fn axes(&self, method: &str) -> Vec<Axis> {
        let Some(m) = methods::by_name(method) else {
            return Vec::new();
        };
        let mut axes = m.axes();
        if !axes.iter().any(|a| a.name() == effects::EFFECT.name()) {
            axes.push(effects::EFFECT);
        }
        axes
    }
    fn validate(&self, method: &str, point: &Point) -> std::result::Result<(), InvalidPoint> {
        match methods::by_name(method) {
            Some(m) => m.validate(point),
            None => Err(InvalidPoint::UnknownMethod(method.to_string())),
        }
    }

    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
        run_methods_group(ctx, emit, &|_, _, _| {})
    }
}

/// The ground truth of one group (its scene at its resolution), computed once, on the first
/// point that needs it, and shared by the group's rows: the exact fragment lists and the
/// reference images composited from them per effect.
pub struct GroupTruth<'a> {
    scene: &'a scenarios::Scene,
    width: u32,
    height: u32,
    lists: OnceCell<FragmentLists>,
    /// Reference images of the lists by effect, shared by the group's rows.
    pub images: TruthCache,
}

impl<'a> GroupTruth<'a> {
    pub fn new(ctx: &GroupCtx<'a>) -> Self {
        GroupTruth {
            scene: ctx.scene,
            width: ctx.group.width,
            height: ctx.group.height,
            lists: OnceCell::new(),
            images: TruthCache::default(),
        }
    }

    /// The exact fragment lists of this scene and resolution, computed once per group.
    pub fn lists(&self) -> &FragmentLists {
        self.lists.get_or_init(|| {
            let lists = rasterize(self.scene, self.width, self.height);
            if lists.total_fragments() == 0 {
                // Every row of this group would compare empty images: valid, never silent.
                eprintln!(
                    "warning: scene {} covers no pixel at {}x{}: every image of it is the background",
                    self.scene.spec.label(),
                    self.width,
                    self.height
                );
            }
            lists
        })
    }

    /// Whether the lists were computed already.
    pub fn has_lists(&self) -> bool {
        self.lists.get().is_some()
    }
}

/// Runs every point of a methods-like group (also used by the `stability` study, which adds
/// its columns through `extra` on each row before it is emitted): time it, read it back, judge
/// it against the ground truth (`judge`), emit one row per point.
pub fn run_methods_group(
    ctx: &GroupCtx<'_>,
    emit: &mut Emit<'_>,
    extra: &dyn Fn(&mut Row, &PointSpec, &GroupTruth<'_>),
) -> Result<()> {
    let truth = GroupTruth::new(ctx);
    let runnable = ready_points(ctx, &truth, emit, extra)?;
    let mut peel_ms: Option<f64> = None;
    if ctx.plan.interleave {
        // All points prepared and sampled in a seeded interleaved order, then judged.
        let items: Vec<(&dyn Method, &bench_core::axes::Point)> = runnable
            .iter()
            .map(|r| (r.method.as_ref(), &ctx.group.points[r.index].point))
            .collect();
        let measured = measure_interleaved(ctx.gpu, ctx.gscene, &items, &ctx.plan);
        for (r, m) in runnable.into_iter().zip(measured) {
            finish_point(ctx, &truth, r, m, &mut peel_ms, emit)?;
        }
    } else {
        for r in runnable {
            let pt = &ctx.group.points[r.index];
            let m = measure(ctx.gpu, ctx.gscene, r.method.as_ref(), &pt.point, &ctx.plan);
            finish_point(ctx, &truth, r, m, &mut peel_ms, emit)?;
        }
    }
    Ok(())
}

/// The points of a methods-like group that can run, each with its row so far (method, axes,
/// effect, payload, `extra`'s columns); a point that cannot (an effect its method does not fold,
/// an adapter without what it needs) is emitted here as a `skipped` row. `depth_peel` first.
pub fn ready_points(
    ctx: &GroupCtx<'_>,
    truth: &GroupTruth<'_>,
    emit: &mut Emit<'_>,
    extra: &dyn Fn(&mut Row, &PointSpec, &GroupTruth<'_>),
) -> Result<Vec<Ready>> {
    // depth_peel first so every other row can carry its speedup over it.
    let mut order: Vec<usize> = (0..ctx.group.points.len()).collect();
    order.sort_by_key(|&i| ctx.group.points[i].method != BASELINE);
    // What can run: a base row per point; what cannot is a skipped row now.
    let mut runnable: Vec<Ready> = Vec::new();
    for i in order {
        let pt = &ctx.group.points[i];
        let method = methods::by_name(&pt.method).expect("checked in points()");
        let mut row = Row::new();
        row.set(cols::METHOD, &pt.method)
            .set(cols::CLAIMS_EXACT, method.exact());
        set_params(&mut row, &pt.point.recorded())?;
        extra(&mut row, pt, truth);
        let effect = match effect_of(method.as_ref(), &pt.point) {
            Ok(e) => e,
            Err(why) => {
                emit(i, skipped_row(row, &why.to_string()))?;
                continue;
            }
        };
        row.set(cols::EFFECT, effect.effect.name());
        if let Some(p) = method.payload(&pt.point) {
            row.set(cols::PAYLOAD, p);
        }
        if effect.effect != effects::Effect::Transparency && !folds_effects(method.as_ref()) {
            let why = format!(
                "{} resolves no effects fold (it stores colour only): it cannot supply {}",
                pt.method,
                effect.effect.name()
            );
            emit(i, skipped_row(row, &why.to_string()))?;
            continue;
        }
        if let Err(why) = methods::supports(method.as_ref(), ctx.gpu, &pt.point) {
            emit(i, skipped_row(row, &why.to_string()))?;
            continue;
        }
        runnable.push(Ready {
            index: i,
            method,
            effect,
            row,
        });
    }
    Ok(runnable)
}

/// A point that can run, with its row so far.
pub struct Ready {
    /// The point's index in its group.
    pub index: usize,
    pub method: Box<dyn Method>,
    pub effect: EffectConfig,
    pub row: Row,
}

/// Reads back, judges and emits one measured point.
fn finish_point(
    ctx: &GroupCtx<'_>,
    truth: &GroupTruth<'_>,
    r: Ready,
    measured: Result<bench_core::measure::Measured<dyn Prepared>>,
    peel_ms: &mut Option<f64>,
    emit: &mut Emit<'_>,
) -> Result<()> {
    let Ready {
        index: i,
        method,
        effect,
        mut row,
    } = r;
    let pt = &ctx.group.points[i];
    let mut m = match measured {
        Ok(m) => m,
        // Under a browser's limits wgpu refuses what exceeds them: that is "does not fit".
        Err(e)
            if !matches!(e, bench_core::CoreError::Limit(_))
                && ctx.gpu.profile.explains(&e.to_string()) =>
        {
            let why = format!("under {} limits: {e}", ctx.gpu.profile.owner());
            return emit(i, skipped_row(row, &why));
        }
        Err(e) => return emit(i, error_row(row, &e)),
    };
    if let Some(s) = m.prepared.split() {
        row.set(cols::SPLIT, s);
    }
    set_timing(&mut row, &m, &ctx.scene.mesh);
    // This study's frames are GPU work only: a wall time far above the GPU time means the
    // timestamps missed work (measure::timestamps_incomplete says how far).
    if let Some(g) = m.gpu_median() {
        if bench_core::measure::timestamps_incomplete(g, m.cpu.median) {
            row.add_flag(Flag::TimestampsIncomplete);
        }
    }
    let px = ctx.gscene.pixels() as f64;
    row.set_f(
        cols::BYTES_PER_PIXEL,
        m.bytes_allocated as f64 / px.max(1.0),
    );
    if !truth.has_lists() {
        let t = std::time::Instant::now();
        truth.lists();
        row.set_f(cols::FRAGMENT_REFERENCE_MS, t.elapsed().as_secs_f64() * 1e3);
    }
    let t_judge = std::time::Instant::now();
    let mut cap = match m.prepared.readback(ctx.gpu, ctx.gscene) {
        Ok(c) => c,
        Err(e) => return emit(i, failed_row(row, &format!("readback: {e}"))),
    };
    let lists = truth.lists();
    m.prepared.judge(&mut cap, lists);
    set_reference_columns(&mut row, lists);
    bench_core::measure::set_fragment_rate(&mut row, lists.total_fragments());
    if let (Some(o), true) = (m.bytes_overhead, lists.total_fragments() > 0) {
        let frag = m.bytes_allocated.saturating_sub(o) as f64;
        row.set_f(
            cols::FRAGMENT_BYTES_RATIO,
            frag / (lists.total_fragments() * 8) as f64,
        );
    }
    row.set_opt(cols::FRAGMENTS_DROPPED, cap.dropped_fragments)
        .set_opt(cols::FRAGMENTS_TAILED, cap.tailed_fragments);
    let cx = judge::Context {
        scene: ctx.scene,
        effect: &effect,
        exact: method.exact(),
        flip: ctx.flip,
        truths: Some(&truth.images),
    };
    let j = match judge::judge(&cap, lists, cx) {
        Ok(j) => j,
        Err(why) => return emit(i, failed_row(row, &why.to_string())),
    };
    j.write(&mut row);
    if let Err(e) = recapture_hazards(&mut row, &mut *m.prepared, ctx.gpu, ctx.gscene, lists) {
        return emit(i, failed_row(row, &format!("hazard recapture: {e}")));
    }
    // Read-back and judging, the group's fragment lists aside (their own column).
    row.set_f(cols::JUDGE_MS, t_judge.elapsed().as_secs_f64() * 1e3);
    if let Some(img) = &cap.image {
        ctx.save_image(&mut row, &pt.method, pt.given(), img)?;
    }
    // No speed-up of (or over) a GPU time that is not the frame's (record::gpu_time_trusted).
    if let Some(g) = m
        .gpu_median()
        .filter(|_| bench_core::record::gpu_time_trusted(&row))
    {
        if pt.method == BASELINE && peel_ms.is_none() {
            *peel_ms = Some(g);
        }
        if let Some(p) = *peel_ms {
            if g > 0.0 {
                row.set_f(cols::SPEEDUP_VS_DEPTH_PEEL, p / g);
            }
        }
    }
    emit(i, row)
}

/// `hazard_captures` > 1 (issue 45 item 8: a verdict on hazard_rate needs an interval): runs,
/// reads back and judges that many frames in all, the timed one's capture first, and writes the
/// lowest and highest hazard rate. Untimed (after the samples); hazard_rate stays the first's.
fn recapture_hazards(
    row: &mut Row,
    prepared: &mut dyn Prepared,
    gpu: &bench_core::gpu::Gpu,
    scene: &bench_core::gpu_scene::GpuScene,
    lists: &FragmentLists,
) -> Result<()> {
    let n = prepared.hazard_captures();
    let Some(first) = row.get_f(cols::HAZARD_RATE).filter(|_| n > 1) else {
        return Ok(());
    };
    let px = lists.pixels().max(1) as f64;
    let mut timer = bench_core::timing::GpuTimer::new(gpu);
    let (mut lo, mut hi) = (first, first);
    for _ in 1..n {
        timer.begin_frame();
        prepared.frame(gpu, scene, &mut timer)?;
        gpu.wait()?;
        let mut cap = prepared.readback(gpu, scene)?;
        prepared.judge(&mut cap, lists);
        let r = cap.hazard_pixels.unwrap_or(0) as f64 / px;
        lo = lo.min(r);
        hi = hi.max(r);
    }
    row.set(cols::HAZARD_CAPTURES, n)
        .set_f(cols::HAZARD_RATE_CI_LO, lo)
        .set_f(cols::HAZARD_RATE_CI_HI, hi);
    Ok(())
}

/// True if some pixel holds two fragments at exactly the same window depth.
pub fn has_depth_ties(lists: &mfx_reference::FragmentLists) -> bool {
    (0..lists.pixels()).any(|p| lists.pixel(p).windows(2).any(|w| w[0].depth == w[1].depth))
}

/// Scene columns that need the reference (depth complexity, true fragments).
pub fn set_reference_columns(row: &mut Row, lists: &mfx_reference::FragmentLists) {
    let dc = lists.depth_complexity();
    let covered = dc.iter().filter(|&&d| d > 0).count();
    row.set(cols::DEPTH_COMPLEXITY_MAX, lists.max_depth_complexity())
        .set_f(
            cols::DEPTH_COMPLEXITY_MEAN,
            lists.total_fragments() as f64 / covered.max(1) as f64,
        )
        .set(cols::TRUE_FRAGMENTS, lists.total_fragments())
        .set(cols::BYTES_TRUE_FRAGMENTS, lists.total_fragments() * 8);
}
