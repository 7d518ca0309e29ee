//! The single-pass floors: one depth-only pass (`floor_depth`, with an empty fragment stage, or
//! `floor_depth_vs` with none) and one opaque single-colour pass (`floor_opaque`).

use crate::gpu::Gpu;
use crate::gpu_scene::{AllocCounter, Attrs, GpuScene};
use crate::gpu_util::{camera_entry, clear_depth, depth_state, shader};
use crate::timed::{FrameStats, Timed};
use crate::timing::GpuTimer;
use crate::Result;

const WGSL: &str = include_str!("floor.wgsl");

/// The three single-pass floors' pipelines.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// Depth only, with an empty fragment stage.
    Depth,
    /// Depth only, no fragment stage.
    DepthVs,
    /// Depth and one constant colour.
    Opaque,
}

pub(super) struct PreparedFloor {
    pipeline: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    depth: wgpu::TextureView,
    color: Option<wgpu::TextureView>,
    alloc: AllocCounter,
    reversed: bool,
}

impl PreparedFloor {
    pub(super) fn new(gpu: &Gpu, scene: &GpuScene, kind: Kind) -> Self {
        let with_color = kind == Kind::Opaque;
        let d = &gpu.device;
        let module = shader(gpu, "floor", WGSL);
        let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("floor"),
            entries: &[camera_entry(0)],
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("floor"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("floor"),
            layout: &bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: scene.camera.as_entire_binding(),
            }],
        });
        let layouts = GpuScene::layouts(Attrs::POSITION_ONLY);
        let targets = [Some(wgpu::ColorTargetState {
            format: wgpu::TextureFormat::Rgba8Unorm,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("floor"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_position"),
                compilation_options: Default::default(),
                buffers: &layouts.iter().map(|l| Some(l.clone())).collect::<Vec<_>>(),
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(depth_state(scene.reversed_z, true)),
            multisample: Default::default(),
            fragment: match kind {
                Kind::DepthVs => None,
                Kind::Depth => Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_none"),
                    compilation_options: Default::default(),
                    targets: &[],
                }),
                Kind::Opaque => Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_constant"),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
            },
            multiview_mask: None,
            cache: None,
        });
        let mut alloc = AllocCounter::default();
        let depth = alloc
            .texture(
                gpu,
                "floor depth",
                scene.width,
                scene.height,
                wgpu::TextureFormat::Depth32Float,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            )
            .create_view(&Default::default());
        let color = with_color.then(|| {
            alloc
                .texture(
                    gpu,
                    "floor colour",
                    scene.width,
                    scene.height,
                    wgpu::TextureFormat::Rgba8Unorm,
                    wgpu::TextureUsages::RENDER_ATTACHMENT,
                )
                .create_view(&Default::default())
        });
        PreparedFloor {
            pipeline,
            bind,
            depth,
            color,
            alloc,
            reversed: scene.reversed_z,
        }
    }
}

impl Timed for PreparedFloor {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let color_att: Vec<Option<wgpu::RenderPassColorAttachment>> = self
                .color
                .iter()
                .map(|v| {
                    Some(wgpu::RenderPassColorAttachment {
                        view: v,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                })
                .collect();
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("floor"),
                color_attachments: &color_att,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear_depth(self.reversed)),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.render_pass("floor"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind, &[]);
            scene.draw(&mut pass, Attrs::POSITION_ONLY);
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
