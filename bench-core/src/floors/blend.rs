//! The unordered-blend floors (LucidRaster's yardstick, Jakubowski 2024: exact OIT is reported
//! as a multiple of *unordered hardware blending*). One pass, both faces, every fragment blended
//! premultiplied-over into an RGBA8 target in primitive order, no depth test, no sort. Two of
//! them, differing only in what the vertex and fragment stages read:
//! - `floor_blend_const`: positions only (12 B a vertex) and one constant colour: the cheapest
//!   honest unordered blend of the scene's fragments, and what `x_blend` divides by. An
//!   independent wgpu probe of this shape agreed with `floor_depth` within 0.1 % on 1.1–1.6M
//!   triangle stacks (issue 33), where the old `floor_blend` took 1.06–1.81× as long.
//! - `floor_blend`: the methods' own vertex stage (`vs_full`: position, normal, colour, object
//!   id, 44 B a vertex in four streams) and each fragment's interpolated colour: what the
//!   methods read before they store a fragment, and no more. Until issue 33 it read position
//!   and colour (28 B, two streams) and was the `x_blend` yardstick; on geometry-bound scenes
//!   the extra vertex streams and varyings, not the blend, made it slower than the probe.
//!
//! Like the other floors they are yardsticks, not methods judged for error: the runner measures
//! them without reading them back. [`super::FloorFrame::image`] still returns the image (RGBA8
//! read as premultiplied f32) so a test can check each is the unordered blend it claims.

use crate::gpu::{read_texture, Gpu};
use crate::gpu_scene::{AllocCounter, Attrs, GpuScene};
use crate::gpu_util::{camera_entry, shader};
use crate::timed::{FrameStats, Timed};
use crate::timing::GpuTimer;
use crate::Result;

const WGSL: &str = include_str!("blend.wgsl");

/// `fs_const`'s colour, premultiplied (blend.wgsl).
pub const CONST_PREMUL: [f32; 4] = [0.25, 0.125, 0.0625, 0.25];

pub(super) struct PreparedBlend {
    attrs: Attrs,
    pipeline: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    target: wgpu::Texture,
    view: wgpu::TextureView,
    alloc: AllocCounter,
}

impl PreparedBlend {
    /// `Attrs::ALL`: `vs_full` + `fs_blend`; `Attrs::POSITION_ONLY`: `vs_position` + `fs_const`.
    pub(super) fn new(gpu: &Gpu, scene: &GpuScene, attrs: Attrs) -> Self {
        let constant = attrs == Attrs::POSITION_ONLY;
        let d = &gpu.device;
        let module = shader(gpu, "floor_blend", WGSL);
        let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("floor_blend"),
            entries: &[camera_entry(0)],
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("floor_blend"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("floor_blend"),
            layout: &bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: scene.camera.as_entire_binding(),
            }],
        });
        let layouts: Vec<_> = GpuScene::layouts(attrs).into_iter().map(Some).collect();
        let targets = [Some(wgpu::ColorTargetState {
            format: wgpu::TextureFormat::Rgba8Unorm,
            blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("floor_blend"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some(if constant { "vs_position" } else { "vs_full" }),
                compilation_options: Default::default(),
                buffers: &layouts,
            },
            // Both faces, as every multi-fragment method sees them.
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(if constant { "fs_const" } else { "fs_blend" }),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let mut alloc = AllocCounter::default();
        let target = alloc.texture(
            gpu,
            "floor_blend colour",
            scene.width,
            scene.height,
            wgpu::TextureFormat::Rgba8Unorm,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let view = target.create_view(&Default::default());
        PreparedBlend {
            attrs,
            pipeline,
            bind,
            target,
            view,
            alloc,
        }
    }
}

impl Timed for PreparedBlend {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("floor_blend"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("floor"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind, &[]);
            scene.draw(&mut pass, self.attrs);
        }
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: 1,
            layers: 1,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl PreparedBlend {
    /// The blended target, RGBA8 read as premultiplied f32.
    pub(super) fn image(&self, gpu: &Gpu) -> Result<Vec<[f32; 4]>> {
        let bytes = read_texture(gpu, &self.target, 4, wgpu::TextureAspect::All)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|p| [0, 1, 2, 3].map(|c| p[c] as f32 / 255.0))
            .collect())
    }
}
