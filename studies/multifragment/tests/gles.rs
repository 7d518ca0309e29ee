//! `--backend gles`: our own EGL display and GLES 3.x context handed to wgpu (`bench_core::gles`).
//! Locally that is Mesa's llvmpipe through EGL's device or surfaceless platform; on an NVIDIA
//! GPU, NVIDIA's EGL. Skipped (with the reason printed) only where no EGL GLES context exists.
//!
//! The point is the compute A-buffer (compute shaders and storage buffers: what GLES 3.1 adds
//! over the desktop GL 3.3 wgpu picks itself on NVIDIA). Depth peeling cannot run on wgpu's GL
//! backend at all: naga's GLSL writer has no `textureLoad` from depth textures.
//! Tolerance: RMSE ≤ 1e-3 (an exact method: f32 compositing of ≤ 16 layers is ~1e-6, one pixel
//! of coverage disagreement at 64² is ~4e-3).

use bench_core::gpu::{BackendChoice, Gpu, GpuOptions};
use mfx_multifragment::effects::reference_image;
use mfx_multifragment::{methods, testing};
use mfx_reference::metrics::{image_error, BAD_PIXEL_TOL};
use mfx_reference::rasterize;
use scenarios::{ParamValue, Params};

#[test]
fn the_gles_adapter_opens_and_a_method_point_matches_the_truth() {
    let _ = env_logger::builder().is_test(true).try_init();
    let opts = GpuOptions {
        backend: BackendChoice::Gles,
        ..Default::default()
    };
    let gpu = match Gpu::new(&opts) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("skipped: no GLES context through EGL on this machine: {e}");
            return;
        }
    };
    assert_eq!(gpu.facts.backend, "gles");
    let info = gpu.adapter.get_info();
    assert!(
        info.driver_info.contains("OpenGL ES"),
        "a GLES context, not desktop GL: {info:?}"
    );
    // GLES 3.1+ is what the backend is for: compute shaders (wgpu reports them as downlevel).
    assert!(
        gpu.downlevel
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS),
        "GLES 3.1+ has compute shaders: {:?} ({info:?})",
        gpu.downlevel.flags
    );

    let scene = testing::scene("quads", &[("depth_complexity", ParamValue::Int(3))]);
    let (w, h) = (64, 64);
    let method = methods::get("compute_abuffer");
    let (cap, _) = testing::render(&gpu, &scene, &*method, &Params::new(), w, h);
    let lists = rasterize(&scene, w, h);
    let reference = reference_image("transparency", &lists, cap.expected).unwrap();
    let e = image_error(&reference, cap.image.as_ref().unwrap(), BAD_PIXEL_TOL);
    assert_eq!(e.non_finite, 0, "NaN/Inf in the GLES image");
    assert!(
        e.rmse <= 1e-3,
        "compute A-buffer on GLES: RMSE {} > 1e-3",
        e.rmse
    );
}
