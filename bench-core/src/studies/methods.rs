//! The `methods` study: every multi-fragment method on every scene, timed, and judged against
//! the exact CPU reference; `speedup_vs_depth_peel` comes from depth_peel in the same group.

use super::{Emit, GroupCtx, Methods, PointSpec, Study};
use crate::axes::{Axis, Point};
use crate::effects::{self, EffectConfig};
use crate::measure::{measure, set_timing};
use crate::method::Method;
use crate::methods::{self, Expected};
use crate::metrics::{image_error, layer_count_accuracy, BAD_PIXEL_TOL};
use crate::record::cols;
use crate::record::Row;
use crate::record::{failed_row, set_params, skipped_row};
use crate::Result;

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
fn effect_of(m: &dyn Method, point: &Point) -> std::result::Result<EffectConfig, String> {
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
    fn kind(&self) -> &'static str {
        "methods"
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
    fn validate(&self, method: &str, point: &Point) -> std::result::Result<(), String> {
        match methods::by_name(method) {
            Some(m) => m.validate(point),
            None => Err(format!("unknown method '{method}'")),
        }
    }

    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
        run_methods_group(ctx, emit, &|_, _| {})
    }
}

/// Runs every point of a methods-like group (also used by the `stability` study, which adds
/// its columns through `extra` on each row before it is emitted).
pub fn run_methods_group(
    ctx: &GroupCtx<'_>,
    emit: &mut Emit<'_>,
    extra: &dyn Fn(&mut Row, &PointSpec),
) -> Result<()> {
    {
        // depth_peel first so every other row can carry its speedup over it.
        let mut order: Vec<usize> = (0..ctx.group.points.len()).collect();
        order.sort_by_key(|&i| ctx.group.points[i].method != BASELINE);
        let mut peel_ms: Option<f64> = None;
        for i in order {
            let pt = &ctx.group.points[i];
            let method = methods::by_name(&pt.method).expect("checked in points()");
            let mut row = Row::new();
            row.set(cols::METHOD, &pt.method)
                .set(cols::EXACT, method.exact());
            set_params(&mut row, pt.point.values())?;
            extra(&mut row, pt);
            let effect = match effect_of(method.as_ref(), &pt.point) {
                Ok(e) => e,
                Err(why) => {
                    emit(i, skipped_row(row, &why))?;
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
                emit(i, skipped_row(row, &why))?;
                continue;
            }
            if let Err(why) = methods::supports(method.as_ref(), ctx.gpu, &pt.point) {
                emit(i, skipped_row(row, &why))?;
                continue;
            }
            let mut m = match measure(
                ctx.gpu,
                ctx.gscene,
                method.as_ref(),
                &pt.point,
                ctx.warmup,
                ctx.reps,
            ) {
                Ok(m) => m,
                Err(e) => {
                    emit(i, failed_row(row, &e.to_string()))?;
                    continue;
                }
            };
            set_timing(&mut row, &m, &ctx.scene.mesh);
            let mut cap = match m.prepared.readback(ctx.gpu, ctx.gscene) {
                Ok(c) => c,
                Err(e) => {
                    emit(i, failed_row(row, &format!("readback: {e}")))?;
                    continue;
                }
            };
            let lists = ctx.reference();
            m.prepared.judge(&mut cap, lists);
            set_reference_columns(&mut row, lists);
            let dc = lists.depth_complexity();
            let k = match cap.expected {
                Expected::All => u32::MAX,
                Expected::FirstK(k) => k,
            };
            // Beyond a FirstK capacity, or as the method counted it (pools, unpeeled layers).
            let overflow = dc
                .iter()
                .filter(|&&d| d > k)
                .count()
                .max(cap.overflow_pixels.unwrap_or(0) as usize);
            row.set_f(
                cols::OVERFLOW_RATE,
                overflow as f64 / dc.len().max(1) as f64,
            );
            let mut flag = cap.flag.clone();
            if overflow > 0 && flag.is_none() {
                flag = Some("overflow".into());
            }
            if let Some(counts) = &cap.counts {
                // Fragments the method should have captured (within its k) but did not. At a
                // pixel whose f64 reference has exact depth ties this is the coplanar loss of
                // strict peeling; elsewhere distinct layers merged in the method's own depth
                // precision (e.g. a large far/near ratio).
                let (mut coplanar, mut precision) = (0u64, 0u64);
                for (p, (&d, &c)) in dc.iter().zip(counts).enumerate() {
                    let lost = d.min(k).saturating_sub(c) as u64;
                    if lost > 0 {
                        let f = lists.pixel(p);
                        if f.windows(2).any(|w| w[0].depth == w[1].depth) {
                            coplanar += lost;
                        } else {
                            precision += lost;
                        }
                    }
                }
                row.set(cols::LOST_FRAGMENTS, coplanar + precision);
                if coplanar > 0 {
                    flag.get_or_insert_with(|| "lost_coplanar".into());
                } else if precision > 0 {
                    flag.get_or_insert_with(|| "precision".into());
                }
            }
            if let Some(img) = &cap.image {
                let reference = effect.reference(ctx.scene, lists, cap.expected);
                if reference.len() != img.len() {
                    let why = format!(
                        "image has {} pixels, the {} reference {}",
                        img.len(),
                        effect.effect.name(),
                        reference.len()
                    );
                    emit(i, failed_row(row, &why))?;
                    continue;
                }
                let e = image_error(&reference, img, BAD_PIXEL_TOL);
                row.set_f(cols::RMSE, e.rmse)
                    .set_f(cols::PSNR_DB, e.psnr_db)
                    .set_f(cols::MAX_ABS_ERR, e.max_abs)
                    .set_f(cols::BAD_PIXEL_FRAC, e.bad_pixel_frac)
                    .set_f(cols::BAD_PIXEL_TOL, BAD_PIXEL_TOL)
                    .set(cols::NON_FINITE, e.non_finite);
                if e.non_finite > 0 {
                    flag.get_or_insert_with(|| "precision".into());
                }
                ctx.save_image(&mut row, &pt.method, pt.given(), img)?;
            }
            if let Some(counts) = &cap.counts {
                let expected: Vec<u32> = dc.iter().map(|&d| d.min(k)).collect();
                row.set_f(
                    cols::LAYER_COUNT_ACCURACY,
                    layer_count_accuracy(&expected, counts),
                );
                row.set(
                    cols::LAYERS_CAPTURED_MAX,
                    counts.iter().max().copied().unwrap_or(0),
                );
            }
            if let Some(c) = cap.collision_fragments {
                row.set_f(
                    cols::COLLISION_RATE,
                    c as f64 / lists.total_fragments().max(1) as f64,
                );
            }
            if let Some(h) = cap.hazard_pixels {
                row.set_f(cols::HAZARD_RATE, h as f64 / dc.len().max(1) as f64);
            }
            if let Some(f) = flag {
                row.set(cols::FLAG, f);
            }
            row.add_note(&cap.notes);
            if let Some(g) = m.gpu_ms.map(|s| s.median) {
                if pt.method == BASELINE && peel_ms.is_none() {
                    peel_ms = Some(g);
                }
                if let Some(p) = peel_ms {
                    if g > 0.0 {
                        row.set_f(cols::SPEEDUP_VS_DEPTH_PEEL, p / g);
                    }
                }
            }
            emit(i, row)?;
        }
        Ok(())
    }
}

/// True if some pixel holds two fragments at exactly the same window depth.
pub fn has_depth_ties(lists: &crate::reference::FragmentLists) -> bool {
    (0..lists.pixels()).any(|p| lists.pixel(p).windows(2).any(|w| w[0].depth == w[1].depth))
}

/// Scene columns that need the reference (depth complexity, true fragments).
pub fn set_reference_columns(row: &mut Row, lists: &crate::reference::FragmentLists) {
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
