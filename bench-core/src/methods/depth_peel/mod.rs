//! Classic depth peeling (Everitt 2001, "Interactive Order-Independent Transparency"): the exact
//! baseline. One geometry pass per layer, front to back; each layer is composited under the
//! accumulated colour by a compute pass. With `occlusion_stop` (default) an occlusion query per
//! pass ends peeling at the first pass that writes nothing (a CPU round trip per pass, as in the
//! original); otherwise exactly `max_layers` passes run in one submission.

use scenarios::Params;

use super::floor::{clear_depth, depth_state};
use super::{
    bool_param, camera_entry, int_param, read_vec, shader, storage_entry, texture_entry, Capture,
    Expected, FrameStats, Method, Prepared,
};
use crate::gpu::Gpu;
use crate::gpu_scene::{AllocCounter, Attrs, GpuScene};
use crate::timing::GpuTimer;
use crate::{CoreError, Result};

const WGSL: &str = include_str!("depth_peel.wgsl");
const LAYER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub struct DepthPeel;

impl Method for DepthPeel {
    fn name(&self) -> &'static str {
        "depth_peel"
    }
    fn describe(&self) -> &'static str {
        "Everitt 2001: exact front-to-back peeling, one geometry pass per layer (+1 empty pass with occlusion_stop)"
    }
    fn exact(&self) -> bool {
        true
    }
    fn axes(&self) -> &'static [&'static str] {
        &["max_layers", "occlusion_stop"]
    }
    fn supports(&self, gpu: &Gpu, params: &Params) -> std::result::Result<(), String> {
        int_param(params, "max_layers", 64, 1, 4096)?;
        bool_param(params, "occlusion_stop", true)?;
        if !gpu.renderable(LAYER_FORMAT) {
            return Err(format!(
                "{LAYER_FORMAT:?} is not renderable on this adapter"
            ));
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, params: &Params) -> Result<Box<dyn Prepared>> {
        let max_layers =
            int_param(params, "max_layers", 64, 1, 4096).map_err(CoreError::Param)? as u32;
        let occlusion_stop =
            bool_param(params, "occlusion_stop", true).map_err(CoreError::Param)?;
        Ok(Box::new(PreparedPeel::new(
            gpu,
            scene,
            max_layers,
            occlusion_stop,
        )))
    }
}

struct PreparedPeel {
    first: wgpu::RenderPipeline,
    peel: wgpu::RenderPipeline,
    composite: wgpu::ComputePipeline,
    /// Per parity p: pass i (i % 2 == p) writes depth[p] and reads depth[1 − p].
    peel_bind: [wgpu::BindGroup; 2],
    composite_bind: [wgpu::BindGroup; 2],
    depth_views: [wgpu::TextureView; 2],
    layer_view: wgpu::TextureView,
    accum: wgpu::Buffer,
    counts: wgpu::Buffer,
    occlusion: wgpu::QuerySet,
    occ_resolve: wgpu::Buffer,
    occ_read: wgpu::Buffer,
    max_layers: u32,
    occlusion_stop: bool,
    reversed: bool,
    alloc: AllocCounter,
}

impl PreparedPeel {
    fn new(gpu: &Gpu, scene: &GpuScene, max_layers: u32, occlusion_stop: bool) -> Self {
        let d = &gpu.device;
        let (w, h) = (scene.width, scene.height);
        let module = shader(gpu, "depth_peel", WGSL);
        let frag = wgpu::ShaderStages::FRAGMENT;
        let comp = wgpu::ShaderStages::COMPUTE;
        let peel_bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("peel"),
            entries: &[
                camera_entry(0),
                texture_entry(1, wgpu::TextureSampleType::Depth, frag),
            ],
        });
        let comp_bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("peel composite"),
            entries: &[
                texture_entry(
                    0,
                    wgpu::TextureSampleType::Float { filterable: false },
                    comp,
                ),
                texture_entry(1, wgpu::TextureSampleType::Depth, comp),
                storage_entry(2, false, comp),
                storage_entry(3, false, comp),
            ],
        });
        let peel_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("peel"),
            bind_group_layouts: &[Some(&peel_bgl)],
            immediate_size: 0,
        });
        let comp_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("peel composite"),
            bind_group_layouts: &[Some(&peel_bgl), Some(&comp_bgl)],
            immediate_size: 0,
        });
        let layouts: Vec<_> = GpuScene::layouts(Attrs::ALL)
            .into_iter()
            .map(Some)
            .collect();
        let targets = [Some(wgpu::ColorTargetState {
            format: LAYER_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let make = |peel: bool| {
            let constants = [("PEEL", if peel { 1.0 } else { 0.0 })];
            let opts = wgpu::PipelineCompilationOptions {
                constants: &constants,
                zero_initialize_workgroup_memory: false,
            };
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(if peel { "peel" } else { "peel first layer" }),
                layout: Some(&peel_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_full"),
                    compilation_options: Default::default(),
                    buffers: &layouts,
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(depth_state(scene.reversed_z, true)),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_peel"),
                    compilation_options: opts,
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let first = make(false);
        let peel = make(true);
        let composite = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("peel composite"),
            layout: Some(&comp_layout),
            module: &module,
            entry_point: Some("composite"),
            compilation_options: Default::default(),
            cache: None,
        });

        let mut alloc = AllocCounter::default();
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let depth_tex = [0, 1].map(|i| {
            alloc.texture(
                gpu,
                &format!("peel depth {i}"),
                w,
                h,
                wgpu::TextureFormat::Depth32Float,
                usage,
            )
        });
        let depth_views = [0, 1].map(|i| depth_tex[i].create_view(&Default::default()));
        let layer_view = alloc
            .texture(gpu, "peel layer", w, h, LAYER_FORMAT, usage)
            .create_view(&Default::default());
        let px = (w * h) as u64;
        let st = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let accum = alloc.buffer(gpu, "peel accum", px * 16, st);
        let counts = alloc.buffer(gpu, "peel counts", px * 4, st);
        let peel_bind = [0usize, 1].map(|p| {
            d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("peel"),
                layout: &peel_bgl,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: scene.camera.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&depth_views[1 - p]),
                    },
                ],
            })
        });
        let composite_bind = [0usize, 1].map(|p| {
            d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("peel composite"),
                layout: &comp_bgl,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&layer_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&depth_views[p]),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: accum.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: counts.as_entire_binding(),
                    },
                ],
            })
        });
        let occlusion = d.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("peel occlusion"),
            ty: wgpu::QueryType::Occlusion,
            count: 1,
        });
        let occ_resolve = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("occlusion resolve"),
            size: 256,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let occ_read = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("occlusion read"),
            size: 8,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        PreparedPeel {
            first,
            peel,
            composite,
            peel_bind,
            composite_bind,
            depth_views,
            layer_view,
            accum,
            counts,
            occlusion,
            occ_resolve,
            occ_read,
            max_layers,
            occlusion_stop,
            reversed: scene.reversed_z,
            alloc,
        }
    }

    /// Encodes peel pass `i` and its composite.
    fn encode_layer(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        i: u32,
    ) {
        let p = (i % 2) as usize;
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("peel"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.layer_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth_views[p],
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear_depth(self.reversed)),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.render_pass("peel"),
                occlusion_query_set: self.occlusion_stop.then_some(&self.occlusion),
                multiview_mask: None,
            });
            pass.set_pipeline(if i == 0 { &self.first } else { &self.peel });
            pass.set_bind_group(0, &self.peel_bind[p], &[]);
            if self.occlusion_stop {
                pass.begin_occlusion_query(0);
            }
            scene.draw(&mut pass, Attrs::ALL);
            if self.occlusion_stop {
                pass.end_occlusion_query();
            }
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("composite"),
                timestamp_writes: timer.compute_pass("composite"),
            });
            pass.set_pipeline(&self.composite);
            pass.set_bind_group(0, &self.peel_bind[p], &[]);
            pass.set_bind_group(1, &self.composite_bind[p], &[]);
            pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
        }
        if self.occlusion_stop {
            enc.resolve_query_set(&self.occlusion, 0..1, &self.occ_resolve, 0);
            enc.copy_buffer_to_buffer(&self.occ_resolve, 0, &self.occ_read, 0, 8);
        }
    }
}

impl Prepared for PreparedPeel {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.accum, 0, None);
        enc.clear_buffer(&self.counts, 0, None);
        let mut stats = FrameStats::default();
        for i in 0..self.max_layers {
            self.encode_layer(&mut enc, scene, timer, i);
            stats.geometry_passes += 1;
            if self.occlusion_stop {
                // The classic algorithm: the CPU reads the query before deciding on another pass.
                gpu.queue.submit([enc.finish()]);
                let bytes = gpu.map_read(&self.occ_read)?;
                let samples = u64::from_le_bytes(bytes[..8].try_into().unwrap());
                if samples == 0 {
                    return Ok(stats);
                }
                stats.layers += 1;
                enc = gpu.device.create_command_encoder(&Default::default());
            } else {
                stats.layers += 1;
            }
        }
        gpu.queue.submit([enc.finish()]);
        Ok(stats)
    }

    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let n = scene.pixels();
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.accum, n)?);
        let counts = read_vec::<u32>(gpu, &self.counts, n)?;
        cap.expected = Expected::FirstK(self.max_layers);
        cap.overflow_pixels = None;
        cap.counts = Some(counts);
        Ok(cap)
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}
