//! Helpers for GPU tests: open the adapter tests run on, and render one method on one scene.

use scenarios::{Params, Scene};

use crate::gpu::{Gpu, GpuOptions};
use crate::gpu_scene::GpuScene;
use crate::methods::{self, Capture, FrameStats};
use crate::runner::measure;

/// The adapter for tests (lavapipe on CI). A machine with no adapter fails the test with a
/// message saying how to install one: a GPU test must not pass by not running.
pub fn gpu() -> Gpu {
    Gpu::new(&GpuOptions::default()).unwrap_or_else(|e| {
        panic!("GPU tests need a Vulkan adapter (run scripts/setup.sh for lavapipe): {e}")
    })
}

/// Prepares `method` on `scene` at w×h, runs one frame and reads it back.
pub fn render(
    gpu: &Gpu,
    scene: &Scene,
    method: &str,
    params: &Params,
    w: u32,
    h: u32,
) -> (Capture, FrameStats) {
    let m = methods::by_name(method).unwrap_or_else(|| panic!("unknown method {method}"));
    if let Err(why) = m.supports(gpu, params) {
        panic!("{method} cannot run on {}: {why}", gpu.facts.name);
    }
    let gs = GpuScene::upload(gpu, scene, w, h);
    let mut measured =
        measure(gpu, &gs, m.as_ref(), params, 0, 1).unwrap_or_else(|e| panic!("{method}: {e}"));
    let cap = measured
        .prepared
        .readback(gpu, &gs)
        .unwrap_or_else(|e| panic!("{method} readback: {e}"));
    (cap, measured.frame)
}
