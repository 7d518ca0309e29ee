//! Layered soft shadow maps against the ray-traced reference, on lavapipe at 64×64 with
//! 64–128² shadow maps and 16×16 reference rays per pixel.

use scenarios::{ParamValue, Params, SceneSpec};

use super::layered::LayeredSsm;
use super::{compare, gbuffer_points, reference, VisError};
use bench_core::axes::Point;
use bench_core::gpu_scene::GpuScene;
use bench_core::measure::{measure_timed, TimingPlan};
use bench_core::testing;

/// A configuration's point, through the declared axes.
fn point(method: &LayeredSsm, p: &Params) -> Point {
    Point::resolve(&method.axes(), p).unwrap_or_else(|e| panic!("{}", e.join("; ")))
}

/// The visibility of one timed frame (`measure_timed` under the one-frame plan).
fn visibility(
    gpu: &bench_core::gpu::Gpu,
    gs: &GpuScene,
    method: &LayeredSsm,
    pt: &Point,
) -> Vec<f32> {
    let make = |s: &GpuScene| Ok(Box::new(method.prepare_ssm(gpu, s, pt)?));
    let m = measure_timed(gpu, gs, &make, &TimingPlan::once()).unwrap();
    m.prepared.read_visibility(gpu, gs).unwrap()
}

const W: u32 = 64;
const M: u32 = 16;

fn scene(case: &str) -> scenarios::Scene {
    SceneSpec::new(
        "soft_shadow",
        Params::new()
            .with("case", ParamValue::Str(case.into()))
            .with("segments", ParamValue::Int(12))
            .with("leaves", ParamValue::Int(40)),
    )
    .build()
    .unwrap()
}

/// Errors of each configuration on `case`, against one shared reference.
fn errors(case: &str, configs: &[Params]) -> Vec<VisError> {
    errors_where(case, configs, |_| true)
}

/// As [`errors`], over the pixels whose surface point satisfies `keep`.
fn errors_where(
    case: &str,
    configs: &[Params],
    keep: impl Fn(glam::DVec3) -> bool,
) -> Vec<VisError> {
    let gpu = testing::gpu();
    let scene = scene(case);
    let gs = GpuScene::upload(gpu, &scene, W, W);
    let method = LayeredSsm::new(scene.area_light.clone().unwrap());
    let points = gbuffer_points(gpu, &gs, &method).unwrap();
    let mut r = reference(&scene, &method.light, &points, W, M);
    for (v, p) in r.vis.iter_mut().zip(&points) {
        if !p.is_some_and(&keep) {
            *v = None;
        }
    }
    configs
        .iter()
        .map(|p| {
            let vis = visibility(gpu, &gs, &method, &point(&method, p));
            compare(&r.vis, &vis)
        })
        .collect()
}

fn cfg(res: i64, layers: i64) -> Params {
    Params::new()
        .with("shadow_map_res", ParamValue::Int(res))
        .with("layers", ParamValue::Int(layers))
}

#[test]
fn quad_over_ground_64px_error_within_one_texel_band() {
    let r = 128.0;
    let e = errors("quad", &[cfg(128, 2)])[0];
    // Geometry of `case = quad` (light 4 above the ground, quad at height 1.5, light side 1):
    // occluder depth z_b = 2.5, ground receivers at z = 4, f = 1/tan(fovy/2) = 4 / 2.625.
    let (zb, z, f, l) = (2.5, 4.0, 4.0 / 2.625, 1.0);
    // The rasterized quad differs from the true one by at most one texel along each edge; one
    // texel at z_b is (2/r)·z_b/f wide and backprojects ×z/(z − z_b) onto the light: a band of
    // the light's (unit) side that is wrongly counted.
    let band = (2.0 / r) * zb / f * z / (z - zb) / l;
    // A corner of the light sees two edges; the reference's m×m strata err by ≤ 1/m per edge.
    let max_bound = 2.0 * band + 2.0 / M as f64;
    assert!(
        e.evaluated > 2000,
        "most of the 64² pixels see lit ground: {e:?}"
    );
    assert_eq!(e.unevaluated + e.non_finite, 0, "{e:?}");
    assert!(
        e.max_abs <= max_bound,
        "max error {} > bound {max_bound}: {e:?}",
        e.max_abs
    );
    // Only penumbra pixels err (umbra and lit pixels are exact), each by less than the bound.
    assert!(
        e.rmse <= band,
        "RMSE {} > one texel band {band}: {e:?}",
        e.rmse
    );
}

#[test]
fn cpu_twin_matches_gpu_shading_on_every_case() {
    let gpu = testing::gpu();
    let configs = [
        cfg(64, 3).with("max_nspp", ParamValue::Int(25)),
        cfg(128, 4)
            .with("bias_mode", ParamValue::Str("slope".into()))
            .with("hsm", ParamValue::Bool(false))
            .with("max_nspp", ParamValue::Int(169)),
        cfg(96, 2).with("bias_mode", ParamValue::Str("midpoint".into())),
        // §5.3.2's near-plane start, with and without the HSM, and §5.2.2's maximum bias.
        cfg(64, 3)
            .with("max_nspp", ParamValue::Int(25))
            .with("search_start", ParamValue::Str("near".into()))
            .with("bias_max", ParamValue::Float(0.05)),
        cfg(96, 2)
            .with("bias_mode", ParamValue::Str("midpoint".into()))
            .with("search_start", ParamValue::Str("near".into()))
            .with("hsm", ParamValue::Bool(false))
            .with("bias_max", ParamValue::Float(0.1)),
    ];
    for case in ["quad", "spheres", "leaves", "slabs", "tangent"] {
        let scene = scene(case);
        let gs = GpuScene::upload(gpu, &scene, W, W);
        let method = LayeredSsm::new(scene.area_light.clone().unwrap());
        for p in &configs {
            let mut prep = method.prepare_ssm(gpu, &gs, &point(&method, p)).unwrap();
            let mut timer = bench_core::timing::GpuTimer::new(gpu);
            timer.begin_frame();
            bench_core::timed::Timed::frame(&mut prep, gpu, &gs, &mut timer).unwrap();
            gpu.wait().unwrap();
            let vis = prep.read_visibility(gpu, &gs).unwrap();
            let maps = prep.read_maps(gpu).unwrap();
            let pts = prep.read_points(gpu, &gs).unwrap();
            let (mut shaded, mut off, mut sum) = (0usize, 0usize, 0.0f64);
            for (g, p) in vis.iter().zip(&pts) {
                let q = p.map(|p| [p[0], p[1], p[2], 1.0]).unwrap_or([0.0; 4]);
                let t = maps.shade_point(q);
                assert_eq!(
                    t < 0.0,
                    *g < 0.0,
                    "{case} {p:?}: evaluated on one side only"
                );
                if t >= 0.0 {
                    shaded += 1;
                    let d = (t - g).abs() as f64;
                    sum += d;
                    off += (d > 1e-3) as usize;
                }
            }
            // Same rule, same f32 inputs: only FMA/ordering rounding differs, which can move a
            // region edge across a texel boundary in a rare pixel.
            assert!(shaded > 1000, "{case}");
            assert!(
                off * 200 <= shaded,
                "{case} {}: {off} of {shaded} pixels differ from the CPU twin by > 1e-3",
                p.label()
            );
            assert!(
                sum / shaded as f64 <= 1e-3,
                "{case} {}: mean |GPU − twin| {}",
                p.label(),
                sum / shaded as f64
            );
        }
    }
}

#[test]
fn leaves_64px_more_layers_cut_ground_overshadowing() {
    // Thin overlapping leaves: from the light's centre the lower leaves hide under the upper
    // ones. Judged on ground receivers (y = 0 exactly), where the thesis makes its claim.
    let configs: Vec<Params> = (1..=4).map(|k| cfg(128, k)).collect();
    let es = errors_where("leaves", &configs, |p| p.y.abs() < 1e-6);
    for (k, e) in es.iter().enumerate() {
        eprintln!("layers {}: {e:?}", k + 1);
    }
    let one = es[0];
    assert!(one.evaluated > 1000, "{one:?}");
    for (k, e) in es.iter().enumerate().skip(1) {
        // With k ≥ 2 the hidden leaves are captured and the deepest occluder's (larger)
        // backprojection replaces the top one's: overshadowing must fall and RMSE not rise.
        assert!(
            e.overshadow < one.overshadow,
            "layers {}: overshadowing {} not below 1 layer's {}",
            k + 1,
            e.overshadow,
            one.overshadow
        );
        assert!(
            e.rmse <= one.rmse,
            "layers {}: RMSE {} above 1 layer's {}",
            k + 1,
            e.rmse,
            one.rmse
        );
    }
}

#[test]
fn hsm_never_drops_an_occluder_at_stride_one() {
    // The HSM only cuts texels whose occluders could not reach the light: any texel left out
    // of the refined region holds depths ≥ the refined z_min, whose backprojection lies outside
    // the light square. With stride 1 (a 64² map: regions ≤ 128 texels < √65536) HSM on and
    // off must therefore agree pixel for pixel; a wrong pyramid (max instead of min, a bad level
    // offset) cuts real occluders and fails here.
    let gpu = testing::gpu();
    for case in ["spheres", "leaves", "tangent"] {
        let scene = scene(case);
        let gs = GpuScene::upload(gpu, &scene, W, W);
        let method = LayeredSsm::new(scene.area_light.clone().unwrap());
        // Both starts: the near plane's region kr(n) (§5.3.2) and the pyramid's global minimum.
        for start in ["near", "global_min"] {
            let vis = |hsm: bool| {
                let p = cfg(64, 3)
                    .with("max_nspp", ParamValue::Int(65536))
                    .with("search_start", ParamValue::Str(start.into()))
                    .with("hsm", ParamValue::Bool(hsm));
                visibility(gpu, &gs, &method, &point(&method, &p))
            };
            let (on, off) = (vis(true), vis(false));
            let worst = on
                .iter()
                .zip(&off)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            // f32 rounding of region edges only.
            assert!(
                worst <= 1e-4,
                "{case} {start}: HSM on/off differ by {worst}"
            );
        }
    }
}

#[test]
fn hsm_shrinks_the_near_plane_region_on_the_wide_light_quad() {
    // §5.5.1's scene (a quad under a wide light, light_size = 3): started from the near plane
    // (§5.3.2), the HSM's two refinements must shrink the mean search region well below kr(n)
    // (here: under half), or the scene cannot show the thesis's speed-up; and the global-minimum
    // start, mfx's first choice, must already be smaller than kr(n) (why it hid the effect).
    let gpu = testing::gpu();
    let scene = SceneSpec::new(
        "soft_shadow",
        Params::new()
            .with("case", ParamValue::Str("quad".into()))
            .with("light_size", ParamValue::Float(3.0)),
    )
    .build()
    .unwrap();
    let gs = GpuScene::upload(gpu, &scene, W, W);
    let method = LayeredSsm::new(scene.area_light.clone().unwrap());
    let p = cfg(128, 3).with("search_start", ParamValue::Str("near".into()));
    let mut prep = method.prepare_ssm(gpu, &gs, &point(&method, &p)).unwrap();
    let mut timer = bench_core::timing::GpuTimer::new(gpu);
    timer.begin_frame();
    bench_core::timed::Timed::frame(&mut prep, gpu, &gs, &mut timer).unwrap();
    gpu.wait().unwrap();
    let mut maps = prep.read_maps(gpu).unwrap();
    let pts: Vec<[f32; 4]> = prep
        .read_points(gpu, &gs)
        .unwrap()
        .iter()
        .filter_map(|p| p.map(|p| [p[0], p[1], p[2], 1.0]))
        .collect();
    let mut mean = |flags: u32| {
        maps.light.cfg[3] = flags;
        let w: Vec<f32> = pts.iter().filter_map(|g| maps.search_width(*g)).collect();
        assert!(w.len() > 1000, "{}", w.len());
        w.iter().map(|&x| x as f64).sum::<f64>() / w.len() as f64
    };
    let (near, near_hsm, global) = (mean(0), mean(1), mean(2));
    eprintln!("mean region: near {near}, near + HSM {near_hsm}, global min {global}");
    assert!(
        near_hsm < 0.5 * near,
        "HSM: {near_hsm} against kr(n) {near}"
    );
    assert!(global < near, "global min {global} against kr(n) {near}");
}

#[test]
fn search_start_and_bias_max_are_checked_axes() {
    let method = LayeredSsm::new(scene("quad").area_light.unwrap());
    for (key, v) in [
        ("search_start", ParamValue::Str("far".into())),
        ("bias_max", ParamValue::Float(-0.1)),
    ] {
        let e = Point::resolve(&method.axes(), &cfg(64, 3).with(key, v))
            .err()
            .unwrap_or_else(|| panic!("{key} accepted"))
            .join("; ");
        assert!(e.contains(key), "{key}: {e}");
    }
}
