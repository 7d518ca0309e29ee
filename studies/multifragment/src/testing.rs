//! Method helpers for tests: a method rendered on a scene, judged against the f64 reference,
//! and the comparisons every method's tests make. The adapter and scenes are the harness's
//! (`bench_core::testing`, re-exported here).

use scenarios::{Params, Scene};

use bench_core::axes::Point;
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::GpuScene;
use bench_core::measure::TimingPlan;
pub use bench_core::testing::{gpu, params, scene};
use mfx_reference::{rasterize, FragmentLists};

use crate::method::{measure, supports, Capture, Expected, FrameStats, Method};

pub use crate::STUDIES;

/// `params` resolved against `method`'s declared axes (a test naming an undeclared axis fails).
pub fn point(method: &dyn Method, params: &Params) -> Point {
    let p = Point::resolve(&method.axes(), params)
        .unwrap_or_else(|e| panic!("{}: {}", method.name(), e.join("; ")));
    method
        .validate(&p)
        .unwrap_or_else(|e| panic!("{}: {e}", method.name()));
    p
}

/// The entries of `params` that `method` declares (a suite's product does the same when one
/// table sweeps several methods).
pub fn declared(method: &dyn Method, params: &Params) -> Params {
    let axes = method.axes();
    Params(
        params
            .0
            .iter()
            .filter(|(k, _)| axes.iter().any(|a| a.name() == k.as_str()))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect(),
    )
}

/// Prepares `method` on `scene` at w×h, runs one frame and reads it back (not judged).
pub fn render(
    gpu: &Gpu,
    scene: &Scene,
    method: &dyn Method,
    params: &Params,
    w: u32,
    h: u32,
) -> (Capture, FrameStats) {
    let name = method.name();
    let p = point(method, params);
    if let Err(why) = supports(method, gpu, &p) {
        panic!("{name} cannot run on {}: {why}", gpu.facts.name);
    }
    let gs = GpuScene::upload(gpu, scene, w, h);
    let mut measured = measure(gpu, &gs, method, &p, &TimingPlan::once())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let cap = measured
        .prepared
        .readback(gpu, &gs)
        .unwrap_or_else(|e| panic!("{name} readback: {e}"));
    (cap, measured.frame)
}

/// One frame of `method` on `scene` at w×h on the test adapter, judged by the method against
/// the reference: the capture and the reference lists.
pub fn run(
    method: &dyn Method,
    scene: &Scene,
    w: u32,
    h: u32,
    params: &Params,
) -> (Capture, FragmentLists) {
    let gpu = gpu();
    let name = method.name();
    let p = point(method, params);
    if let Err(why) = supports(method, gpu, &p) {
        panic!("{name} cannot run on {}: {why}", gpu.facts.name);
    }
    let gs = GpuScene::upload(gpu, scene, w, h);
    let mut m = measure(gpu, &gs, method, &p, &TimingPlan::once())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut cap = m
        .prepared
        .readback(gpu, &gs)
        .unwrap_or_else(|e| panic!("{name} readback: {e}"));
    let lists = rasterize(scene, w, h);
    m.prepared.judge(&mut cap, &lists);
    (cap, lists)
}

/// The transparency reference of the set a capture is judged against (all or k nearest).
pub fn reference_of(cap: &Capture, lists: &FragmentLists) -> Vec<[f64; 4]> {
    match cap.expected {
        Expected::All => lists.composite(),
        Expected::FirstK(k) => lists.composite_first(k as usize),
    }
}

/// Largest per-channel error of `cap`'s image against the transparency reference of its
/// `expected` set, and the pixel where it is (NaN counts as the worst).
pub fn max_err(cap: &Capture, lists: &FragmentLists) -> (f64, usize) {
    max_err_vs(cap, &reference_of(cap, lists))
}

/// One frame of `method` on `scene` (as [`run`]) and the ground truth its image is judged
/// against (`aa::ground_truth`): the multisampled truth of the capture's `aa` mode, or the
/// single-sample reference, of the point's effect (transparency for a method without effects).
pub fn run_truth(
    method: &dyn Method,
    scene: &Scene,
    w: u32,
    h: u32,
    params: &Params,
) -> (Capture, Vec<[f64; 4]>) {
    let (cap, lists) = run(method, scene, w, h, params);
    let p = point(method, params);
    let effect = if method
        .axes()
        .iter()
        .any(|a| a.name() == crate::effects::EFFECT.name())
    {
        crate::effects::EffectConfig::from_point(&p).expect("validated")
    } else {
        Default::default()
    };
    let truth = crate::aa::ground_truth(&cap, scene, &lists, &effect);
    (cap, truth)
}

/// Largest per-channel error of `cap`'s image against `reference`, and the pixel where it is
/// (NaN counts as the worst).
pub fn max_err_vs(cap: &Capture, reference: &[[f64; 4]]) -> (f64, usize) {
    let img = cap.image.as_ref().expect("an image");
    assert_eq!(img.len(), reference.len(), "image and reference sizes");
    let mut worst = (0.0f64, 0usize);
    for (p, (r, g)) in reference.iter().zip(img).enumerate() {
        for c in 0..4 {
            let e = (r[c] - g[c] as f64).abs();
            if e.is_nan() || e > worst.0 {
                worst = (if e.is_nan() { f64::INFINITY } else { e }, p);
            }
        }
    }
    worst
}

/// Pixels whose captured count differs from min(true depth complexity, k), and the first one.
pub fn count_mismatch(cap: &Capture, lists: &FragmentLists, k: u32) -> (usize, Option<usize>) {
    let counts = cap.counts.as_ref().expect("counts");
    let dc = lists.depth_complexity();
    let bad: Vec<usize> = (0..dc.len())
        .filter(|&p| counts[p] != dc[p].min(k))
        .collect();
    (bad.len(), bad.first().copied())
}

/// Runs `method` on every scene at every point of `points` (its parameters) at w×h and asserts
/// its image matches the reference of its expected set within `tol` (`why`: the tolerance's
/// reason, in the message) and its counts match min(depth complexity, k) where it reports
/// counts; `also` checks what else the caller's method promises (no hazard, no overflow) on
/// each capture, named "scene params".
pub fn assert_matches_reference(
    method: &dyn Method,
    scenes: &[&Scene],
    points: &[Params],
    (w, h): (u32, u32),
    tol: f64,
    why: &str,
    also: impl Fn(&str, &Capture),
) {
    for scene in scenes {
        for p in points {
            let name = format!(
                "{} {} at {w}x{h}, {}",
                method.name(),
                scene.label(),
                p.label()
            );
            let (cap, lists) = run(method, scene, w, h, p);
            let (err, px) = max_err(&cap, &lists);
            assert!(
                err <= tol,
                "{name}: max error {err:.3e} at pixel {px} (tolerance {tol:e}: {why})"
            );
            if cap.counts.is_some() {
                let cap_k = match cap.expected {
                    Expected::All => u32::MAX,
                    Expected::FirstK(k) => k,
                };
                let (bad, first) = count_mismatch(&cap, &lists, cap_k);
                assert_eq!(
                    bad, 0,
                    "{name}: {bad} pixels with the wrong fragment count (first: {first:?})"
                );
            }
            also(&name, &cap);
        }
    }
}

/// Six 1.6-wide grey quads (α 0.3, object ids 0–5) at z 0, 0.5 and `hidden_z` + 0, 0.1, 0.2,
/// 0.3: with `hidden_z` behind the eye, a scene whose later frames bring four quads into view
/// (the overflow tests of sized captures).
pub fn quads_with_four_at(hidden_z: f32) -> scenarios::Mesh {
    let mut m = scenarios::Mesh::default();
    let zs = [
        0.0,
        0.5,
        hidden_z,
        hidden_z + 0.1,
        hidden_z + 0.2,
        hidden_z + 0.3,
    ];
    for (i, z) in zs.into_iter().enumerate() {
        let h = 0.8;
        let c = [
            glam::Vec3::new(-h, -h, z),
            glam::Vec3::new(h, -h, z),
            glam::Vec3::new(h, h, z),
            glam::Vec3::new(-h, h, z),
        ];
        m.push_quad(c, [0.5, 0.5, 0.5, 0.3], i as u32);
    }
    m
}
