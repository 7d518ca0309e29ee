//! The `shadows` study (issue 7): layered soft shadow maps (Bavoil 2007, thesis ch. 5) from a
//! square area light, swept over their quality parameters and judged against a CPU ray tracer.
//!
//! Per scene × resolution group: one untimed frame gives the eye's G-buffer points; the ray
//! tracer ([`raytrace`]) shoots `shadow_rays` stratified rays per pixel from exactly those points
//! (cached across groups of the same scene, resolution and ray count); then every point (a
//! configuration of [`layered::AXES`]) is timed by the runner's `measure` and its visibility is
//! compared pixel by pixel: RMSE, signed mean (light bleeding > 0, overshadowing < 0), max.
//! Images (reference, result, signed difference) go to `$MFX_OUT_DIR/images/shadows/` when the
//! CLI sets it (`mfx sweep` does).
//!
//! Study keys: `shadow_rays` (m², default 64), `images` (default true).

pub mod layered;
pub mod raytrace;
pub mod twin;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use glam::{DVec3, Vec3};
use scenarios::{ParamValue, Params, StudySpec};

use bench_core::axes::{Axis, Point};
use bench_core::measure::{measure_timed, set_timing};
use bench_core::record::Row;
use bench_core::record::{cols, Flag};
use bench_core::record::{error_row, failed_row, set_params, skipped_row};
use bench_core::study::{Emit, GroupCtx, InvalidPoint, Methods, Opt, PointSpec, Study, StudyKind};
use bench_core::timed::Timed;
use bench_core::timing::GpuTimer;
use bench_core::{CoreError, Result};
use layered::{Config, LayeredSsm};
use raytrace::{Bvh, LightFrame};

const METHOD: &str = "layered_ssm";
const SHADOW_RAYS: Opt = Opt {
    name: "shadow_rays",
    doc: "reference rays per pixel: a perfect square m² (the light square's m×m strata)",
    kind: scenarios::ValueKind::Int {
        default: 64,
        min: 1,
        max: 4096 * 4096,
    },
};
const IMAGES: Opt = Opt {
    name: "images",
    doc: "write visibility images beside the CSV",
    kind: scenarios::ValueKind::Bool { default: true },
};

pub struct ShadowsStudy;

/// Study-table settings (outside the swept axes).
struct Settings {
    /// Rays per axis of the light square (shadow_rays = m²).
    rays_per_axis: u32,
    images: bool,
}

/// `shadow_rays` as rays per axis, or why it is not a perfect square.
fn rays_per_axis(spec: &StudySpec) -> std::result::Result<u32, InvalidPoint> {
    let rays = SHADOW_RAYS.int(spec);
    let m = (rays.max(0) as f64).sqrt().round() as i64;
    if !(1..=4096).contains(&m) || m * m != rays {
        return Err(InvalidPoint::value(
            SHADOW_RAYS.name,
            rays,
            "must be a perfect square m² with 1 ≤ m ≤ 4096 (the strata are m×m)",
        ));
    }
    Ok(m as u32)
}

fn settings(spec: &StudySpec) -> Result<Settings> {
    Ok(Settings {
        rays_per_axis: rays_per_axis(spec)?,
        images: IMAGES.bool(spec),
    })
}

impl Study for ShadowsStudy {
    fn kind(&self) -> StudyKind {
        StudyKind::Shadows
    }
    fn describe(&self) -> &'static str {
        "layered soft shadow maps (Bavoil ch. 5) from a square area light vs a ray-traced reference"
    }
    fn methods(&self) -> Methods {
        Methods::Implicit(METHOD)
    }
    fn axes(&self, _: &str) -> Vec<Axis> {
        layered::AXES.to_vec()
    }
    fn options(&self) -> Vec<Opt> {
        vec![SHADOW_RAYS, IMAGES]
    }
    fn check_table(&self, spec: &StudySpec) -> Vec<String> {
        rays_per_axis(spec)
            .err()
            .into_iter()
            .map(|e| e.to_string())
            .collect()
    }

    fn run_group(&self, ctx: &GroupCtx<'_>, emit: &mut Emit<'_>) -> Result<()> {
        let set = settings(ctx.study)?;
        let base_row = |point: &Point| -> Result<Row> {
            let mut row = Row::new();
            row.set(cols::METHOD, METHOD).set(cols::CLAIMS_EXACT, false);
            set_params(&mut row, &point.recorded())?;
            row.set(cols::SHADOW_RAYS, set.rays_per_axis * set.rays_per_axis);
            Ok(row)
        };
        let Some(light) = ctx.scene.area_light.clone() else {
            for (i, p) in ctx.group.points.iter().enumerate() {
                let why = format!(
                    "scene {} has no area light (use the soft_shadow generator)",
                    ctx.scene.label()
                );
                emit(i, skipped_row(base_row(&p.point)?, &why))?;
            }
            return Ok(());
        };
        let method = LayeredSsm::new(light);
        let reference = match group_reference(ctx, &method, set.rays_per_axis) {
            Ok(r) => r,
            Err(e) => {
                for (i, p) in ctx.group.points.iter().enumerate() {
                    emit(
                        i,
                        failed_row(base_row(&p.point)?, &format!("reference: {e}")),
                    )?;
                }
                return Ok(());
            }
        };
        let (w, h) = (ctx.group.width, ctx.group.height);
        let img_dir = if set.images {
            std::env::var_os("MFX_OUT_DIR").map(|d| {
                PathBuf::from(d)
                    .join("images")
                    .join("shadows")
                    .join(format!(
                        "{}-{}-{w}x{h}",
                        ctx.group.study_index,
                        sanitize(&ctx.scene.label())
                    ))
            })
        } else {
            None
        };
        if let Some(dir) = &img_dir {
            std::fs::create_dir_all(dir)
                .map_err(|e| CoreError::Io(format!("{}: {e}", dir.display())))?;
            write_visibility_png(&dir.join("reference.png"), w, h, &reference.vis)?;
        }
        // Images of the last point of each layer count: with the suite's ascending axis values
        // that is its finest configuration (largest shadow map and max_nspp).
        let layers_of = |p: &PointSpec| Some(Config::from_point(&p.point).layers);
        let imaged: Vec<usize> = (0..ctx.group.points.len())
            .filter(|&i| {
                let k = layers_of(&ctx.group.points[i]);
                k.is_some() && ctx.group.points[i + 1..].iter().all(|q| layers_of(q) != k)
            })
            .collect();
        for (i, pt) in ctx.group.points.iter().enumerate() {
            let mut row = base_row(&pt.point)?;
            row.set_f(cols::REFERENCE_MS, reference.ms);
            if let Err(why) = method.supports(ctx.gpu, &pt.point) {
                emit(i, skipped_row(row, &why))?;
                continue;
            }
            let make = |gs: &bench_core::gpu_scene::GpuScene| -> Result<Box<layered::PreparedSsm>> {
                Ok(Box::new(method.prepare_ssm(ctx.gpu, gs, &pt.point)?))
            };
            let m = match measure_timed(ctx.gpu, ctx.gscene, &make, &ctx.plan) {
                Ok(m) => m,
                Err(e) => {
                    emit(i, error_row(row, &e))?;
                    continue;
                }
            };
            set_timing(&mut row, &m, &ctx.scene.mesh);
            // Visibility of the last timed frame; −1 where not evaluated, masked by `compare`.
            let got: Vec<f32> = match m.prepared.read_visibility(ctx.gpu, ctx.gscene) {
                Ok(v) => v,
                Err(e) => {
                    emit(i, failed_row(row, &format!("readback: {e}")))?;
                    continue;
                }
            };
            let e = compare(&reference.vis, &got);
            row.set(cols::SHADOW_PIXELS, e.evaluated)
                .set_f(cols::VIS_RMSE, e.rmse)
                .set_f(cols::VIS_BIAS, e.bias)
                .set_f(cols::VIS_MAX_ABS_ERR, e.max_abs)
                .set_f(cols::VIS_BLEED_MEAN, e.bleed)
                .set_f(cols::VIS_OVERSHADOW_MEAN, e.overshadow);
            if e.unevaluated > 0 || e.non_finite > 0 {
                // Added, never set: set_timing may already have flagged the row noisy.
                row.add_flag(Flag::Precision).add_note(&format!(
                    "{} reference pixels the GPU did not evaluate, {} non-finite (counted as error 1)",
                    e.unevaluated, e.non_finite
                ));
            }
            if let Some(dir) = &img_dir {
                if imaged.contains(&i) {
                    let k = layers_of(pt).unwrap_or(0);
                    let stem = format!("p{i}-layers{k}");
                    let vis: Vec<Option<f64>> = got
                        .iter()
                        .map(|&v| (v >= 0.0).then_some(v as f64))
                        .collect();
                    write_visibility_png(&dir.join(format!("{stem}-result.png")), w, h, &vis)?;
                    write_diff_png(
                        &dir.join(format!("{stem}-diff.png")),
                        w,
                        h,
                        &reference.vis,
                        &got,
                    )?;
                }
            }
            emit(i, row)?;
        }
        Ok(())
    }
}

/// Ray-traced visibility of a group's pixels (None where not evaluated) and its cost.
pub struct Reference {
    pub vis: Vec<Option<f64>>,
    pub ms: f64,
}

/// Recent references by scene|resolution|rays: a suite's several studies share a scene.
static CACHE: Mutex<Vec<(String, Arc<Reference>)>> = Mutex::new(Vec::new());
const CACHE_ENTRIES: usize = 8;

fn group_reference(ctx: &GroupCtx<'_>, method: &LayeredSsm, m: u32) -> Result<Arc<Reference>> {
    let key = format!(
        "{}|{}x{}|{m}",
        ctx.scene.label(),
        ctx.group.width,
        ctx.group.height
    );
    if let Some((_, r)) = CACHE.lock().unwrap().iter().find(|(k, _)| *k == key) {
        return Ok(r.clone());
    }
    let points = gbuffer_points(ctx.gpu, ctx.gscene, method)?;
    let r = Arc::new(reference(
        ctx.scene,
        &method.light,
        &points,
        ctx.group.width,
        m,
    ));
    let mut cache = CACHE.lock().unwrap();
    cache.push((key, r.clone()));
    if cache.len() > CACHE_ENTRIES {
        cache.remove(0);
    }
    Ok(r)
}

/// One untimed frame of the cheapest configuration: the eye's G-buffer does not depend on it.
pub fn gbuffer_points(
    gpu: &bench_core::Gpu,
    gscene: &bench_core::gpu_scene::GpuScene,
    method: &LayeredSsm,
) -> Result<Vec<Option<DVec3>>> {
    let params = Params::new()
        .with("shadow_map_res", ParamValue::Int(16))
        .with("layers", ParamValue::Int(1))
        .with("max_nspp", ParamValue::Int(1));
    let point =
        Point::resolve(layered::AXES, &params).map_err(|e| CoreError::Param(e.join("; ")))?;
    method
        .supports(gpu, &point)
        .map_err(|e| CoreError::Param(e.into()))?;
    let mut prep = method.prepare_ssm(gpu, gscene, &point)?;
    let mut timer = GpuTimer::new(gpu);
    timer.begin_frame();
    prep.frame(gpu, gscene, &mut timer)?;
    gpu.wait()?;
    Ok(prep
        .read_points(gpu, gscene)?
        .into_iter()
        .map(|p| p.map(|p| Vec3::from(p).as_dvec3()))
        .collect())
}

/// The reference over the points the light can see: in front of its near plane and inside its
/// frustum (the same test the shader makes, in f64), None elsewhere.
pub fn reference(
    scene: &scenarios::Scene,
    light: &scenarios::AreaLight,
    points: &[Option<DVec3>],
    width: u32,
    m: u32,
) -> Reference {
    let t0 = std::time::Instant::now();
    let bvh = Bvh::from_scene(scene);
    let frame = LightFrame::of(light);
    let f = 1.0 / (light.camera.fovy * 0.5).tan();
    let inside: Vec<Option<DVec3>> = points
        .iter()
        .map(|p| {
            p.filter(|p| {
                let v = *p - frame.center;
                let z = v.dot(frame.forward);
                let x = v.dot(frame.right) * f / z;
                let y = v.dot(frame.up) * f / z;
                z > light.camera.near && x.abs() <= 1.0 && y.abs() <= 1.0
            })
        })
        .collect();
    let vis = raytrace::visibility_image(&bvh, &frame, &inside, width as usize, m);
    Reference {
        vis,
        ms: t0.elapsed().as_secs_f64() * 1e3,
    }
}

/// Visibility error over the pixels the reference evaluates.
#[derive(Clone, Copy, Debug, Default)]
pub struct VisError {
    pub evaluated: u64,
    pub rmse: f64,
    /// Signed mean (GPU − reference).
    pub bias: f64,
    pub max_abs: f64,
    pub bleed: f64,
    pub overshadow: f64,
    /// Reference pixels the GPU marked as not evaluated (−1).
    pub unevaluated: u64,
    pub non_finite: u64,
}

pub fn compare(reference: &[Option<f64>], got: &[f32]) -> VisError {
    let mut e = VisError::default();
    let (mut se, mut sum, mut bl, mut os) = (0.0, 0.0, 0.0, 0.0);
    for (r, &g) in reference.iter().zip(got) {
        let Some(r) = r else { continue };
        e.evaluated += 1;
        let d = if !g.is_finite() {
            e.non_finite += 1;
            1.0
        } else if g < 0.0 {
            e.unevaluated += 1;
            1.0
        } else {
            g as f64 - r
        };
        se += d * d;
        sum += d;
        bl += d.max(0.0);
        os += (-d).max(0.0);
        e.max_abs = e.max_abs.max(d.abs());
    }
    let n = e.evaluated.max(1) as f64;
    e.rmse = (se / n).sqrt();
    e.bias = sum / n;
    e.bleed = bl / n;
    e.overshadow = os / n;
    e
}

/// A scene label as a folder name: `soft_shadow(case=leaves)` → `soft_shadow_case=leaves`.
fn sanitize(s: &str) -> String {
    let keep = |c: char| c.is_ascii_alphanumeric() || matches!(c, '=' | '-' | '.');
    s.chars()
        .map(|c| if keep(c) { c } else { '_' })
        .collect::<String>()
        .trim_matches('_')
        .to_string()
}

/// Grey visibility (black = in shadow); pixels not evaluated in dark blue.
pub fn write_visibility_png(
    path: &std::path::Path,
    w: u32,
    h: u32,
    vis: &[Option<f64>],
) -> Result<()> {
    let mut bytes = Vec::with_capacity(vis.len() * 3);
    for v in vis {
        match v {
            Some(v) => {
                let g = (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                bytes.extend_from_slice(&[g, g, g]);
            }
            None => bytes.extend_from_slice(&[20, 20, 60]),
        }
    }
    image::save_buffer(path, &bytes, w, h, image::ColorType::Rgb8)
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))
}

/// Signed difference GPU − reference: red = light bleeding, blue = overshadowing, full colour at
/// |difference| ≥ 0.5; black where equal, dark grey where not evaluated.
pub fn write_diff_png(
    path: &std::path::Path,
    w: u32,
    h: u32,
    reference: &[Option<f64>],
    got: &[f32],
) -> Result<()> {
    let mut bytes = Vec::with_capacity(reference.len() * 3);
    for (r, &g) in reference.iter().zip(got) {
        match r {
            Some(r) => {
                let d = g as f64 - r;
                let red = ((d * 2.0).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                let blue = ((-d * 2.0).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                bytes.extend_from_slice(&[red, 0, blue]);
            }
            None => bytes.extend_from_slice(&[40, 40, 40]),
        }
    }
    image::save_buffer(path, &bytes, w, h, image::ColorType::Rgb8)
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests;

/// This crate's study kind (the binary's table, `mfx::STUDIES`, lists it with the others).
pub const STUDIES: &[&dyn bench_core::study::Study] = &[&ShadowsStudy];
