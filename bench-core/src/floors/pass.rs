//! The floor rows: one depth-only pass (`floor_depth`), one opaque single-colour pass
//! (`floor_opaque`) and two unsorted alpha-blended passes (`floor_blend`, `floor_blend_const`,
//! in `blend.rs`) over exactly the scene's geometry and resolution. Every method's `x_floor` is its time over
//! `floor_depth` of the same scene in the same run (`x_blend`: over `floor_blend_const`).

mod blend;
pub use blend::{FloorBlend, FloorBlendConst, CONST_PREMUL};

use crate::axes::Point;
use crate::gpu_util::{camera_entry, clear_depth, depth_state, shader};

use super::{Capture, FrameStats, Method, Prepared};
use crate::gpu::Gpu;
use crate::gpu_scene::{AllocCounter, Attrs, GpuScene};
use crate::timing::GpuTimer;
use crate::Result;

const WGSL: &str = include_str!("floor.wgsl");

pub struct FloorDepth;
pub struct FloorDepthVs;
pub struct FloorOpaque;

/// The three single-pass floors' pipelines.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Depth only, with an empty fragment stage.
    Depth,
    /// Depth only, no fragment stage.
    DepthVs,
    /// Depth and one constant colour.
    Opaque,
}

impl Method for FloorDepth {
    fn name(&self) -> &'static str {
        "floor_depth"
    }
    fn describe(&self) -> &'static str {
        "yardstick: one depth-only pass (positions only, an empty fragment shader); no image"
    }
    fn exact(&self) -> bool {
        false
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, _: &Point) -> Result<Box<dyn Prepared>> {
        Ok(Box::new(PreparedFloor::new(gpu, scene, Kind::Depth)))
    }
}

/// The depth-only pass without a fragment stage: `floor_depth` until 2026-12-02. Measured on
/// the H200 (`results/reference/2026-12-02-h200-floors`): its time depended on which render
/// pipeline the process had run last — shells(16, 256) at 1024² took 1.041 ms right after WBOIT
/// or the compute A-buffer and 1.465 ms right after the RMW k-buffer or ADP, settled or not,
/// pooled or dedicated memory — as if a pipeline without a fragment stage inherited state the
/// one before it left. Kept as a method to watch that.
impl Method for FloorDepthVs {
    fn name(&self) -> &'static str {
        "floor_depth_vs"
    }
    fn describe(&self) -> &'static str {
        "yardstick variant: one depth-only pass with no fragment stage at all (the old floor_depth); no image"
    }
    fn exact(&self) -> bool {
        false
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, _: &Point) -> Result<Box<dyn Prepared>> {
        Ok(Box::new(PreparedFloor::new(gpu, scene, Kind::DepthVs)))
    }
}

impl Method for FloorOpaque {
    fn name(&self) -> &'static str {
        "floor_opaque"
    }
    fn describe(&self) -> &'static str {
        "yardstick: one opaque single-colour pass (positions only, RGBA8 + depth); no image"
    }
    fn exact(&self) -> bool {
        false
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, _: &Point) -> Result<Box<dyn Prepared>> {
        Ok(Box::new(PreparedFloor::new(gpu, scene, Kind::Opaque)))
    }
}

struct PreparedFloor {
    pipeline: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    depth: wgpu::TextureView,
    color: Option<wgpu::TextureView>,
    alloc: AllocCounter,
    reversed: bool,
}

impl PreparedFloor {
    fn new(gpu: &Gpu, scene: &GpuScene, kind: Kind) -> Self {
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

impl crate::timed::Timed for PreparedFloor {
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

impl Prepared for PreparedFloor {
    fn readback(&mut self, _: &Gpu, _: &GpuScene) -> Result<Capture> {
        Ok(Capture::empty())
    }
}
