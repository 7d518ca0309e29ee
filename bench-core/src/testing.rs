//! The one adapter for GPU tests: cached once per test binary (lavapipe on CI), and small scenes
//! from a generator's parameters. Suites are run through `runner::run_suite` with the caller's
//! study table. A machine with no adapter fails the test with a message saying how to install
//! one: a GPU test must not pass by not running. (Method helpers: `mfx_multifragment::testing`.)

use std::sync::OnceLock;

use scenarios::{ParamValue, Params, Scene, SceneSpec};

use crate::gpu::{Gpu, GpuOptions};

/// The adapter tests run on, opened once per test binary.
pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| {
        if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
            std::env::set_var("XDG_RUNTIME_DIR", "/tmp");
        }
        Gpu::new(&GpuOptions::default()).unwrap_or_else(|e| {
            panic!("GPU tests need a Vulkan adapter (run scripts/setup.sh for lavapipe): {e}")
        })
    })
}

/// Parameters from `(name, value)` pairs.
pub fn params(kv: &[(&str, ParamValue)]) -> Params {
    let mut p = Params::new();
    for (k, v) in kv {
        p.set(k, v.clone());
    }
    p
}

/// A generator's scene from `(name, value)` pairs.
pub fn scene(generator: &str, kv: &[(&str, ParamValue)]) -> Scene {
    SceneSpec::new(generator, params(kv))
        .build()
        .unwrap_or_else(|e| panic!("scene {generator}: {e}"))
}
