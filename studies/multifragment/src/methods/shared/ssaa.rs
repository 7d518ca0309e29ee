//! `aa = ssaa2x2` for any method that writes its image to a buffer: the method is prepared on
//! the scene at twice the width and height (its own camera uniform, the same projection), and
//! each frame ends with a timed compute pass that box-filters every 2×2 block into the output
//! image. Memory and time are the method's at 4× the pixels plus the output image.

use crate::methods::{Capture, FrameStats, Prepared};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, GpuScene};
use bench_core::gpu_util::{bind_buffers, compute_pipeline, read_vec, storage_entry, STORAGE_RW};
use bench_core::timing::GpuTimer;
use bench_core::{CoreError, Result};
use mfx_reference::AaMode;

const WGSL: &str = r#"
struct Dims { w: u32, h: u32, images: u32, pad: u32 };
@group(0) @binding(0) var<storage, read> dims: Dims;
@group(0) @binding(1) var<storage, read> big: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn box2x2(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= dims.w || id.y >= dims.h {
        return;
    }
    let w2 = 2u * dims.w;
    let n = dims.w * dims.h;
    let p = 2u * id.y * w2 + 2u * id.x;
    for (var k = 0u; k < dims.images; k = k + 1u) {
        let b = k * 4u * n + p;
        out[k * n + id.y * dims.w + id.x] = 0.25 * (big[b] + big[b + 1u] + big[b + w2] + big[b + w2 + 1u]);
    }
}
"#;

struct Supersampled {
    inner: Box<dyn Prepared>,
    big: GpuScene,
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    out: wgpu::Buffer,
    images: usize,
    alloc: AllocCounter,
}

/// Prepares `make` on `scene` at 2× width and height and wraps it in the 2×2 box filter.
pub fn prepare(
    gpu: &Gpu,
    scene: &GpuScene,
    make: impl FnOnce(&GpuScene) -> Result<Box<dyn Prepared>>,
) -> Result<Box<dyn Prepared>> {
    let big = scene.at_resolution(gpu, 2 * scene.width, 2 * scene.height);
    let inner = make(&big)?;
    let src = inner
        .image_buffer()
        .ok_or_else(|| CoreError::Param("ssaa2x2 needs the method's image in a buffer".into()))?;
    let big_px = big.pixels() as u64;
    let images = (src.size() / (16 * big_px)).max(1) as usize;
    let d = &gpu.device;
    let cs = wgpu::ShaderStages::COMPUTE;
    let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("ssaa"),
        entries: &[
            storage_entry(0, true, cs),
            storage_entry(1, true, cs),
            storage_entry(2, false, cs),
        ],
    });
    let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("ssaa"),
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("ssaa box filter"),
        source: wgpu::ShaderSource::Wgsl(WGSL.into()),
    });
    let pipeline = compute_pipeline(
        gpu,
        "ssaa box filter",
        &layout,
        &module,
        "box2x2",
        &[],
        false,
    );
    let mut alloc = AllocCounter::default();
    let dims = wgpu::util::DeviceExt::create_buffer_init(
        d,
        &wgpu::util::BufferInitDescriptor {
            label: Some("ssaa dims"),
            contents: bytemuck::cast_slice(&[scene.width, scene.height, images as u32, 0]),
            usage: wgpu::BufferUsages::STORAGE,
        },
    );
    let out = alloc.buffer(
        gpu,
        "ssaa image",
        scene.pixels() as u64 * 16 * images as u64,
        STORAGE_RW,
    );
    let bind = bind_buffers(gpu, "ssaa", &bgl, &[&dims, src, &out]);
    Ok(Box::new(Supersampled {
        inner,
        big,
        pipeline,
        bind,
        out,
        images,
        alloc,
    }))
}

impl bench_core::timed::Timed for Supersampled {
    fn frame(&mut self, gpu: &Gpu, _: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let stats = self.inner.frame(gpu, &self.big, timer)?;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("ssaa resolve"),
                timestamp_writes: timer.compute_pass("ssaa_resolve"),
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind, &[]);
            let (w, h) = (self.big.width / 2, self.big.height / 2);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        gpu.queue.submit([enc.finish()]);
        Ok(stats)
    }

    fn bytes_allocated(&self) -> u64 {
        self.inner.bytes_allocated() + self.alloc.bytes
    }

    fn bytes_overhead(&self) -> Option<u64> {
        self.inner.bytes_overhead().map(|b| b + self.alloc.bytes)
    }
}

impl Prepared for Supersampled {
    fn split(&self) -> Option<String> {
        self.inner.split()
    }
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let mut cap = self.inner.readback(gpu, &self.big)?;
        cap.image = Some(read_vec::<[f32; 4]>(
            gpu,
            &self.out,
            scene.pixels() * self.images,
        )?);
        // Counts are per supersample (4 per pixel): not comparable with the pixel's reference.
        cap.counts = None;
        cap.aa = Some(AaMode::Ssaa2x2);
        if let Some(o) = cap.overflow_pixels {
            cap.notes = format!(
                "{}{}ssaa2x2: overflow counted in supersamples ({o} of {})",
                cap.notes,
                if cap.notes.is_empty() { "" } else { "; " },
                self.big.pixels()
            );
            // An output pixel overflowed where any of its 4 supersamples did: at least ⌈o/4⌉.
            cap.overflow_pixels = Some(o.div_ceil(4).min(scene.pixels() as u64));
        }
        Ok(cap)
    }

    fn image_buffer(&self) -> Option<&wgpu::Buffer> {
        Some(&self.out)
    }

    fn judge(&mut self, _cap: &mut Capture, _reference: &mfx_reference::FragmentLists) {
        // The inner method's own judge reads a 2w×2h reference; the runner's is w×h, so the
        // method-specific judgement (hazards, definitions) is not made for supersampled rows.
    }
}
