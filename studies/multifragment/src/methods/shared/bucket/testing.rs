//! Test harness shared by the bucket methods' tests: a lavapipe device, scene builders, one
//! frame under a validation scope, and the twin-vs-GPU comparisons that name the bad pixel.

use glam::{DVec3, Vec3};
use scenarios::{Camera, Mesh, ParamValue, Params, Scene, SceneSpec};

use super::{
    box_quads, captured_in_pixel, padded_box, route_pixel_in, Config, Fx, PreparedBucket, RangePass,
};
use crate::methods::{Capture, Prepared, Timed};
use bench_core::gpu_scene::GpuScene;
use bench_core::timing::GpuTimer;
use mfx_reference::{self as reference, FragmentLists};

pub use crate::testing::gpu;

/// `quads` with `d` screen-parallel layers (untilted: each layer has one window depth).
pub fn quads(d: i64, seed: i64) -> Scene {
    quads_z(d, seed, false)
}

/// `quads` with the depth convention chosen (reversed-Z: 1 at the near plane).
pub fn quads_z(d: i64, seed: i64, reversed_z: bool) -> Scene {
    let p = Params::new()
        .with("depth_complexity", ParamValue::Int(d))
        .with("seed", ParamValue::Int(seed))
        .with("reversed_z", ParamValue::Bool(reversed_z));
    SceneSpec::new("quads", p).build().expect("quads scene")
}

/// Screen-parallel quads at the given z (camera at z = 10 looking at the origin); quad i has
/// half-extent 1 − 0.04·i so outer pixels see only some layers.
pub fn quads_at(zs: &[f32], alpha: f32) -> Scene {
    let mut m = Mesh::default();
    for (i, &z) in zs.iter().enumerate() {
        let h = 1.0 - 0.04 * i as f32;
        let c = [
            Vec3::new(-h, -h, z),
            Vec3::new(h, -h, z),
            Vec3::new(h, h, z),
            Vec3::new(-h, h, z),
        ];
        m.push_quad(c, scenarios::scenes::palette(i as u32, alpha), i as u32);
    }
    let cam = Camera::look_at(DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO, 20.0, 1.0, 100.0);
    Scene::new(SceneSpec::new("test", Params::new()), m, cam)
}

pub struct Run {
    pub prepared: PreparedBucket,
    pub capture: Capture,
    pub gscene: GpuScene,
    pub lists: FragmentLists,
    pub geometry_passes: u32,
    /// `range_pass = bounding_box`: each pixel's (zmin, zmax) from the reference rasterizer's
    /// fragments of the same padded box (f64, rounded to f32 as the range target stores it);
    /// None where the box covers nothing.
    pub box_ranges: Option<Vec<Option<(f32, f32)>>>,
}

/// The reference per-pixel range of the scene's padded bounding box: its 6 faces rasterized by
/// the f64 reference under the scene's camera, nearest and farthest depth per pixel.
pub fn box_ranges(scene: &Scene, size: u32) -> Vec<Option<(f32, f32)>> {
    let (lo, hi) = padded_box(&scene.mesh.positions);
    let mut m = Mesh::default();
    for q in box_quads(lo, hi) {
        m.push_quad(q.map(Vec3::from), [1.0; 4], 0);
    }
    let boxed = Scene::new(
        SceneSpec::new("box", Params::new()),
        m,
        scene.camera.clone(),
    );
    let lists = reference::rasterize(&boxed, size, size);
    (0..lists.pixels())
        .map(|p| {
            let ds = lists.pixel(p).iter().map(|f| f.depth);
            let lo = ds.clone().fold(f64::INFINITY, f64::min);
            let hi = ds.fold(f64::NEG_INFINITY, f64::max);
            (lo <= hi).then_some((lo as f32, hi as f32))
        })
        .collect()
}

/// Prepares, renders one frame and reads it back under a validation scope; rasterizes the reference.
pub fn run(cfg: Config, wgsl: &str, scene: &Scene, size: u32) -> Run {
    run_range(cfg, wgsl, scene, size, RangePass::Mesh)
}

/// As [`run`], the depth range drawn from `range`.
pub fn run_range(cfg: Config, wgsl: &str, scene: &Scene, size: u32, range: RangePass) -> Run {
    let gpu = gpu();
    let gscene = GpuScene::upload(gpu, scene, size, size);
    let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let fx = Fx {
        effect: Default::default(),
        pairs: false,
    };
    let mut prepared =
        PreparedBucket::with_range(gpu, &gscene, cfg, wgsl, fx, range).expect("prepare");
    let mut timer = GpuTimer::new(gpu);
    timer.begin_frame();
    let stats = prepared.frame(gpu, &gscene, &mut timer).expect("frame");
    gpu.wait().unwrap();
    let capture = prepared.readback(gpu, &gscene).expect("readback");
    if let Some(e) = pollster::block_on(scope.pop()) {
        panic!("wgpu validation error: {e}");
    }
    let lists = reference::rasterize(scene, size, size);
    let box_ranges = (range == RangePass::BoundingBox).then(|| box_ranges(scene, size));
    Run {
        prepared,
        capture,
        gscene,
        lists,
        geometry_passes: stats.geometry_passes,
        box_ranges,
    }
}

impl Run {
    /// Asserts the GPU's captured count equals the twin's in every pixel, naming the first
    /// pixel that differs with its fragments' routing; returns the twin's collision total.
    pub fn assert_counts_match_twin(&self, cfg: &Config) -> u64 {
        let counts = self.capture.counts.as_ref().expect("counts");
        let truth = self.prepared.count_fragments(gpu(), &self.gscene).unwrap();
        let w = self.lists.width as usize;
        let mut twin_total = 0u64;
        for p in 0..self.lists.pixels() {
            let frags = self.lists.pixel(p);
            assert_eq!(
                truth[p] as usize,
                frags.len(),
                "pixel ({}, {}): GPU rasterized {} fragments, the reference {}",
                p % w,
                p / w,
                truth[p],
                frags.len()
            );
            let range = self
                .box_ranges
                .as_ref()
                .filter(|_| !frags.is_empty())
                .map(|b| {
                    b[p].unwrap_or_else(|| {
                        panic!(
                            "pixel ({}, {}): {} fragments where the reference box covers nothing",
                            p % w,
                            p / w,
                            frags.len()
                        )
                    })
                });
            let routed = route_pixel_in(cfg, frags, self.lists.reversed_z, range);
            let want = captured_in_pixel(cfg, &routed);
            assert_eq!(
                counts[p],
                want,
                "pixel ({}, {}): GPU captured {} fragments, twin {}; twin routing: {:?}",
                p % w,
                p / w,
                counts[p],
                want,
                routed
            );
            twin_total += (frags.len() as u32 - want) as u64;
        }
        assert_eq!(self.capture.collision_fragments, Some(twin_total));
        twin_total
    }

    /// Largest channel difference between the GPU image and `want`, with its pixel.
    pub fn max_err(&self, want: &[[f64; 4]]) -> (f64, usize) {
        let img = self.capture.image.as_ref().expect("image");
        let mut worst = (0.0f64, 0usize);
        for (p, (g, r)) in img.iter().zip(want).enumerate() {
            for c in 0..4 {
                let e = (g[c] as f64 - r[c]).abs();
                if e > worst.0 || e.is_nan() {
                    worst = (e, p);
                }
            }
        }
        worst
    }
}

/// The reference composite with each fragment's colour passed through `quantise` (the
/// packing's twin): what a collision-free bucket method must produce up to f32 rounding.
pub fn quantised_reference(
    lists: &FragmentLists,
    quantise: impl Fn([f32; 4]) -> [f32; 4],
) -> Vec<[f64; 4]> {
    (0..lists.pixels())
        .map(|p| {
            let mut acc = [0.0f64; 4];
            for f in lists.pixel(p) {
                let c = quantise(f.color.map(|x| x as f32)).map(|x| x as f64);
                let t = 1.0 - acc[3];
                for k in 0..3 {
                    acc[k] += t * c[3] * c[k];
                }
                acc[3] += t * c[3];
            }
            acc
        })
        .collect()
}
