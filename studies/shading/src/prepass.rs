//! The light pre-pass renderer (issue 10; Engel 2008/09, and Blur's lighting on other
//! processors). Per frame:
//!
//! 1. pre-pass: depth + view normal/smoothness only (12 B per pixel, `GBufferPass` prepass);
//! 2. light accumulation into the light buffer — Σ diffuse light in RGB, Σ lum(contrib)·spec
//!    in A — by `naive` (fullscreen, every light), `tiled` (the deferred study's compute tile
//!    culling, same kernel in its LIGHT_BUFFER permutation) or `cpu` (below);
//! 3. second geometry pass: the scene again (depth test ≤ the pre-pass depth, no writes); each
//!    material reads the light buffer its own way (`prepass.wgsl`: dielectric vs metal).
//!
//! Light buffer formats: RGBA8 (light stored ÷ 8, clamped), RGBA16F, and RG11B10 + R16F (no
//! alpha in RG11B10: the specular term goes to a second target; needs RG11B10UFLOAT_RENDERABLE;
//! written by the naive pass or packed on the CPU, not by the tiled compute kernel).
//!
//! The `cpu` accumulation: after the pre-pass, depth and normal are copied into MAP_READ
//! buffers; `map_async` callbacks signal readiness and the CPU blocks in
//! `device.poll(Wait { submission_index: pre-pass })` — a blocking wait in the driver, no spin
//! on a flag — then worker threads (`cpu_tiled`, atomic tile counter, SoA quads) fill the light
//! buffer, `queue.write_texture` uploads it and the second pass is submitted. With `overlap`,
//! an independent view (a second camera, full deferred shading) is submitted right after the
//! pre-pass, so the GPU renders it while the CPU lights; without, it is submitted after the
//! second pass. Both orders produce the same two images.

use bench_core::gpu_util::{
    camera_entry, compute_pipeline, depth_state, shader, storage_entry, texture_entry,
};
use std::collections::BTreeMap;
use std::time::Instant;

use scenarios::Scene;

use super::cpu_tiled::{self, CpuOptions};
use super::gbuffer::{padded_row, read_rgba32f, GBufferPass};
use super::gpu_paths::{bge, module, paths_source, Deferred, Path, ShadeInputs, HDR_FORMAT};
use super::{GBuffer, ShadeSetup, SKY, SKY_MATERIAL};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::record::{cols, Col};

use bench_core::study::InvalidPoint;
use bench_core::timed::{FrameStats, PassSpan, Timed};
use bench_core::timing::GpuTimer;
use bench_core::{CoreError, Result, Unsupported};

const WGSL: &str = include_str!("prepass.wgsl");

/// A timed part with no column of its own (`Timed::parts` keys every part by a `Col`): the CPU
/// side's whole frame (decode + light + pack + upload), whose median the row's notes say.
pub const CPU_TOTAL_MS: Col = Col::new(
    "cpu_total_ms",
    "pre-pass, CPU lighting: decode + light + pack + upload per frame, ms (a part: in the notes, not a column)",
);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LbFormat {
    Rgba8,
    Rgba16F,
    Rg11b10,
}

impl LbFormat {
    pub fn parse(s: &str) -> std::result::Result<LbFormat, InvalidPoint> {
        match s {
            "rgba8" => Ok(LbFormat::Rgba8),
            "rgba16f" => Ok(LbFormat::Rgba16F),
            "rg11b10" => Ok(LbFormat::Rg11b10),
            o => Err(InvalidPoint::value(
                "light_buffer_format",
                format!("'{o}'"),
                "is not one of rgba8, rgba16f, rg11b10",
            )),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            LbFormat::Rgba8 => "rgba8",
            LbFormat::Rgba16F => "rgba16f",
            LbFormat::Rg11b10 => "rg11b10",
        }
    }
    fn formats(self) -> (wgpu::TextureFormat, Option<wgpu::TextureFormat>) {
        match self {
            LbFormat::Rgba8 => (wgpu::TextureFormat::Rgba8Unorm, None),
            LbFormat::Rgba16F => (wgpu::TextureFormat::Rgba16Float, None),
            LbFormat::Rg11b10 => (
                wgpu::TextureFormat::Rg11b10Ufloat,
                Some(wgpu::TextureFormat::R16Float),
            ),
        }
    }
    /// Stored = light × scale (RGBA8 holds 0..8 in 0..1).
    pub fn scale(self) -> f32 {
        if self == LbFormat::Rgba8 {
            1.0 / 8.0
        } else {
            1.0
        }
    }
    pub fn bytes_per_pixel(self) -> u64 {
        match self {
            LbFormat::Rgba8 => 4,
            LbFormat::Rgba16F => 8,
            LbFormat::Rg11b10 => 6,
        }
    }
    fn wgsl_storage(self) -> &'static str {
        match self {
            LbFormat::Rgba8 => "rgba8unorm",
            _ => "rgba16float",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accum {
    Naive,
    Tiled {
        tile: u32,
    },
    Cpu {
        threads: usize,
        overlap: bool,
        host: HostWork,
    },
}

/// How the host's work around the CPU lighting runs: the depth/normal decode, the reorder of
/// the lit tiles into rows, and the light buffer's pack into its texture format.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HostWork {
    /// Split across the lighting's own workers (a rayon pool of `threads`), as the SPEs do all
    /// of a tile's work (the chapter: the SPEs light the buffer while the RSX renders other
    /// views; BF3: "Unpack Gbuffer+Z Data -> Shade -> Pack to fp16 -> DMA out" per tile): no
    /// single-threaded pass over the frame besides the upload's copy.
    #[default]
    Parallel,
    /// mfx's earlier host: decode, reorder and pack on one thread around the workers.
    Serial,
}

impl HostWork {
    pub const NAMES: &'static [&'static str] = &["parallel", "serial"];
    pub fn parse(s: &str) -> Option<HostWork> {
        match s {
            "parallel" => Some(HostWork::Parallel),
            "serial" => Some(HostWork::Serial),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            HostWork::Parallel => "parallel",
            HostWork::Serial => "serial",
        }
    }
}

/// Why a pre-pass point cannot run here (a `skipped` row).
pub fn supports(gpu: &Gpu, f: LbFormat, accum: Accum) -> std::result::Result<(), Unsupported> {
    if f == LbFormat::Rg11b10 {
        if !gpu.has(wgpu::Features::RG11B10UFLOAT_RENDERABLE) {
            return Err("adapter lacks RG11B10UFLOAT_RENDERABLE".into());
        }
        if matches!(accum, Accum::Tiled { .. }) {
            return Err(
                "RG11B10 light buffer: the tiled compute kernel cannot write it (not a storage format); naive and cpu can"
                    .into(),
            );
        }
    }
    if let Accum::Tiled { tile } = accum {
        if ![8, 16, 32, 64].contains(&tile) {
            return Err(Unsupported::new(format!(
                "tile_size {tile} is not one of 8, 16, 32, 64"
            )));
        }
    }
    Ok(())
}

enum AccumKind {
    Frag(wgpu::RenderPipeline),
    Tiled {
        pipeline: wgpu::ComputePipeline,
        bind2: wgpu::BindGroup,
        groups: (u32, u32),
    },
    Cpu {
        staging_depth: wgpu::Buffer,
        staging_normal: wgpu::Buffer,
        setup: Box<ShadeSetup>,
        lights: Vec<super::GpuLight>,
        threads: usize,
        overlap: bool,
        host: HostWork,
        /// The workers' pool for the parallel host work (`threads` threads).
        pool: Option<rayon::ThreadPool>,
    },
}

/// Per-frame facts of the CPU path (the last frame's; `samples` keeps every frame's).
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuFrame {
    /// Blocking wait from submitting the pre-pass to the depth/normal map being ready.
    pub map_wait_ms: f64,
    pub cpu_light_ms: f64,
    /// Decode + light + pack + upload on the CPU.
    pub cpu_total_ms: f64,
    /// Submitting the pre-pass to the main view's final image being complete on the GPU.
    pub latency_ms: f64,
    /// Submitting the pre-pass to the CPU-lit light buffer uploaded (the material pass that
    /// reads it is submitted right after).
    pub light_ready_ms: f64,
}

pub struct PrePass {
    pub format: LbFormat,
    pub accum: Accum,
    pub gbuf: GBufferPass,
    inputs: ShadeInputs,
    pub lb0: wgpu::Texture,
    pub lb1: Option<wgpu::Texture>,
    kind: AccumKind,
    second: wgpu::RenderPipeline,
    bind_cam: wgpu::BindGroup,
    bind_mat: wgpu::BindGroup,
    pub hdr: wgpu::Texture,
    depth_view: wgpu::TextureView,
    /// The independent view (second camera) rendered alongside, if any.
    pub view2: Option<(GpuScene, Deferred)>,
    alloc: AllocCounter,
    pub samples: Vec<CpuFrame>,
}

/// The scene seen from behind (the "rear-view mirror"): an independent view of the same scene.
pub fn second_camera(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let e = s.camera.eye;
    let t = s.camera.target;
    s.camera.eye = [-e[0], e[1], -e[2]];
    s.camera.target = [-t[0], t[1], -t[2]];
    s
}

impl PrePass {
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        gscene: &GpuScene,
        format: LbFormat,
        accum: Accum,
        tau: f64,
        second_view: bool,
    ) -> Result<PrePass> {
        supports(gpu, format, accum).map_err(|e| CoreError::Param(e.into()))?;
        let d = &gpu.device;
        let (w, h) = (gscene.width, gscene.height);
        let mut alloc = AllocCounter::default();
        let setup = ShadeSetup::new(scene, w, h);
        let gbuf = GBufferPass::new(gpu, scene, gscene, true, &mut alloc);
        let tile = match accum {
            Accum::Tiled { tile } => tile,
            _ => 16,
        };
        let tiles = (w.div_ceil(tile), h.div_ceil(tile));
        let inputs = ShadeInputs::new(gpu, &setup, &gbuf, tau, tiles, tile, None, &mut alloc);
        let (f0, f1) = format.formats();
        let mut lb_usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST;
        if matches!(accum, Accum::Tiled { .. }) {
            lb_usage |= wgpu::TextureUsages::STORAGE_BINDING;
        }
        let lb0 = alloc.texture(gpu, "light buffer", w, h, f0, lb_usage);
        let lb1 = f1.map(|f| alloc.texture(gpu, "light buffer spec", w, h, f, lb_usage));
        let consts = [("LIGHT_BUFFER", 1.0), ("LB_SCALE", format.scale() as f64)];
        let kind = match accum {
            Accum::Naive => {
                let m = &inputs.module;
                let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("light accumulation"),
                    bind_group_layouts: &[Some(&inputs.bgl0), Some(&inputs.bgl1)],
                    immediate_size: 0,
                });
                let copts = wgpu::PipelineCompilationOptions {
                    constants: &consts,
                    zero_initialize_workgroup_memory: true,
                };
                let mut targets = vec![Some(wgpu::ColorTargetState {
                    format: f0,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })];
                if let Some(f) = f1 {
                    targets.push(Some(wgpu::ColorTargetState {
                        format: f,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    }));
                }
                AccumKind::Frag(d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("light accumulation"),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: m,
                        entry_point: Some("vs_fullscreen"),
                        compilation_options: copts.clone(),
                        buffers: &[],
                    },
                    primitive: Default::default(),
                    depth_stencil: None,
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: m,
                        entry_point: Some(if f1.is_some() {
                            "fs_shade_split"
                        } else {
                            "fs_shade"
                        }),
                        compilation_options: copts,
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                }))
            }
            Accum::Tiled { tile } => {
                // The deferred tile kernel, its output declared in the light buffer's format.
                let src = paths_source().replace(
                    "texture_storage_2d<rgba32float, write>",
                    &format!("texture_storage_2d<{}, write>", format.wgsl_storage()),
                );
                let m = module(gpu, "light accumulation (tiled)", &src);
                let (bgl2, layout) =
                    super::gpu_paths::tiled_layout(gpu, &inputs, "tiled light buffer", f0);
                let n = (tiles.0 * tiles.1) as u64;
                let e = wgpu::BufferUsages::empty();
                let counts =
                    super::gpu_paths::storage_buf(gpu, &mut alloc, "tile counts", n * 4, e);
                let lists = super::gpu_paths::storage_buf(gpu, &mut alloc, "tile lists", 16, e);
                let wg = if tile == 8 { 8 } else { 16 };
                let c = [
                    ("TILE", tile as f64),
                    ("WG", wg as f64),
                    ("PPT", (tile / wg) as f64),
                    ("LIGHT_BUFFER", 1.0),
                    ("LB_SCALE", format.scale() as f64),
                ];
                let pipeline =
                    compute_pipeline(gpu, "tiled light buffer", &layout, &m, "cs_tiled", &c, true);
                let view = lb0.create_view(&Default::default());
                let bind2 = d.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("tiled light buffer"),
                    layout: &bgl2,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::TextureView(&view),
                        },
                        bge(1, &counts),
                        bge(2, &lists),
                    ],
                });
                AccumKind::Tiled {
                    pipeline,
                    bind2,
                    groups: tiles,
                }
            }
            Accum::Cpu {
                threads,
                overlap,
                host,
            } => {
                let mut mk = |label, bpp| {
                    alloc.buffer(
                        gpu,
                        label,
                        padded_row(w, bpp) as u64 * h as u64,
                        wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    )
                };
                let staging_depth = mk("depth to CPU", 4);
                let staging_normal = mk("normal to CPU", 8);
                AccumKind::Cpu {
                    staging_depth,
                    staging_normal,
                    lights: setup.gpu_lights(tau),
                    setup: Box::new(setup.clone()),
                    threads,
                    overlap,
                    host,
                    pool: match host {
                        HostWork::Parallel => Some(
                            rayon::ThreadPoolBuilder::new()
                                .num_threads(threads.max(1))
                                .build()
                                .map_err(|e| CoreError::Gpu(format!("thread pool: {e}")))?,
                        ),
                        HostWork::Serial => None,
                    },
                }
            }
        };
        // Second geometry pass.
        let m2 = shader(gpu, "prepass material", WGSL);
        let bgl_cam = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material camera"),
            entries: &[camera_entry(0)],
        });
        let ff = wgpu::TextureSampleType::Float { filterable: false };
        let fs = wgpu::ShaderStages::FRAGMENT;
        let bgl_mat = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material inputs"),
            entries: &[
                storage_entry(0, true, fs),
                texture_entry(1, ff, fs),
                texture_entry(2, ff, fs),
            ],
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("material"),
            bind_group_layouts: &[Some(&bgl_cam), Some(&bgl_mat)],
            immediate_size: 0,
        });
        let c2 = [
            ("SPLIT", if f1.is_some() { 1.0 } else { 0.0 }),
            ("LB_DECODE", 1.0 / format.scale() as f64),
        ];
        let copts = wgpu::PipelineCompilationOptions {
            constants: &c2,
            zero_initialize_workgroup_memory: true,
        };
        let layouts = GpuScene::layouts(Attrs::ALL);
        let mut ds = depth_state(gscene.reversed_z, false);
        ds.depth_compare = Some(if gscene.reversed_z {
            wgpu::CompareFunction::GreaterEqual
        } else {
            wgpu::CompareFunction::LessEqual
        });
        let second = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("material"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &m2,
                entry_point: Some("vs_full"),
                compilation_options: copts.clone(),
                buffers: &layouts.iter().map(|l| Some(l.clone())).collect::<Vec<_>>(),
            },
            primitive: Default::default(),
            depth_stencil: Some(ds),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &m2,
                entry_point: Some("fs_material"),
                compilation_options: copts,
                targets: &[Some(wgpu::ColorTargetState {
                    format: HDR_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let bind_cam = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("material camera"),
            layout: &bgl_cam,
            entries: &[bge(0, &gscene.camera)],
        });
        let v0 = lb0.create_view(&Default::default());
        let v1 = lb1
            .as_ref()
            .unwrap_or(&lb0)
            .create_view(&Default::default());
        let bind_mat = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("material inputs"),
            layout: &bgl_mat,
            entries: &[
                bge(0, &gbuf.materials),
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&v0),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&v1),
                },
            ],
        });
        let hdr = alloc.texture(
            gpu,
            "hdr",
            w,
            h,
            HDR_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let view2 = if second_view {
            let s2 = second_camera(scene);
            let gs2 = GpuScene::upload(gpu, &s2, w, h);
            let d2 = Deferred::new(
                gpu,
                &s2,
                &gs2,
                Path::Tiled {
                    tile: 16,
                    levels: 1,
                },
                tau,
                false,
            )?;
            alloc.bytes += d2_bytes(&d2);
            Some((gs2, d2))
        } else {
            None
        };
        let depth_view = gbuf.depth.create_view(&Default::default());
        Ok(PrePass {
            format,
            accum,
            gbuf,
            inputs,
            lb0,
            lb1,
            kind,
            second,
            bind_cam,
            bind_mat,
            hdr,
            depth_view,
            view2,
            alloc,
            samples: Vec::new(),
        })
    }

    fn encode_accum_gpu(&self, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        let inp = &self.inputs;
        let bind1 = inp.bind1.as_ref().expect("stand-in surface group");
        match &self.kind {
            AccumKind::Frag(p) => {
                let v0 = self.lb0.create_view(&Default::default());
                let v1 = self
                    .lb1
                    .as_ref()
                    .map(|t| t.create_view(&Default::default()));
                let mut att = vec![Some(wgpu::RenderPassColorAttachment {
                    view: &v0,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })];
                if let Some(v1) = &v1 {
                    att.push(Some(wgpu::RenderPassColorAttachment {
                        view: v1,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    }));
                }
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("light accumulation"),
                    color_attachments: &att,
                    depth_stencil_attachment: None,
                    timestamp_writes: timer.render_pass("lights"),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(p);
                pass.set_bind_group(0, &inp.bind0, &[]);
                pass.set_bind_group(1, bind1, &[]);
                pass.draw(0..3, 0..1);
            }
            AccumKind::Tiled {
                pipeline,
                bind2,
                groups,
            } => {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("light accumulation (tiled)"),
                    timestamp_writes: timer.compute_pass("lights"),
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &inp.bind0, &[]);
                pass.set_bind_group(1, bind1, &[]);
                pass.set_bind_group(2, bind2, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
            }
            AccumKind::Cpu { .. } => {}
        }
    }

    fn encode_second(
        &self,
        enc: &mut wgpu::CommandEncoder,
        gscene: &GpuScene,
        timer: &mut GpuTimer,
    ) {
        let hv = self.hdr.create_view(&Default::default());
        let att = [bench_core::gpu::cleared(
            &hv,
            wgpu::Color {
                r: SKY[0] as f64,
                g: SKY[1] as f64,
                b: SKY[2] as f64,
                a: 1.0,
            },
        )];
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("material"),
            color_attachments: &att,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.render_pass("material"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.second);
        pass.set_bind_group(0, &self.bind_cam, &[]);
        pass.set_bind_group(1, &self.bind_mat, &[]);
        gscene.draw(&mut pass, Attrs::ALL);
    }

    fn submit_view2(&self, gpu: &Gpu, timer: &mut GpuTimer) {
        if let Some((gs2, d2)) = &self.view2 {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            d2.gbuf.encode(&mut enc, gs2, timer, "view2 gbuffer");
            d2.encode_shading_labelled(&mut enc, timer, "view2 ");
            gpu.queue.submit([enc.finish()]);
        }
    }

    pub fn read_image(&self, gpu: &Gpu) -> Result<Vec<[f32; 4]>> {
        read_rgba32f(gpu, &self.hdr)
    }

    /// The light buffer decoded to f32 (light units: the format's scale undone).
    pub fn read_light_buffer(&self, gpu: &Gpu) -> Result<Vec<[f32; 4]>> {
        use super::gbuffer::read_texture;
        let all = wgpu::TextureAspect::All;
        let inv = 1.0 / self.format.scale();
        Ok(match self.format {
            LbFormat::Rgba8 => read_texture(gpu, &self.lb0, 4, all)?
                .chunks(4)
                .map(|c| std::array::from_fn(|i| c[i] as f32 / 255.0 * inv))
                .collect(),
            LbFormat::Rgba16F => {
                let b = read_texture(gpu, &self.lb0, 8, all)?;
                let hs: &[u16] = bytemuck::cast_slice(&b);
                hs.chunks(4)
                    .map(|c| std::array::from_fn(|i| half::f16::from_bits(c[i]).to_f32()))
                    .collect()
            }
            LbFormat::Rg11b10 => {
                let b = read_texture(gpu, &self.lb0, 4, all)?;
                let spec = read_texture(
                    gpu,
                    self.lb1.as_ref().expect("rg11b10 has a specular target"),
                    2,
                    all,
                )?;
                let hs: &[u16] = bytemuck::cast_slice(&spec);
                bytemuck::cast_slice::<u8, u32>(&b)
                    .iter()
                    .zip(hs)
                    .map(|(&p, &a)| {
                        let c = unpack_rg11b10(p);
                        [c[0], c[1], c[2], half::f16::from_bits(a).to_f32()]
                    })
                    .collect()
            }
        })
    }

    /// Render-target bytes per frame of the main view, one touch per pixel (overdraw and the
    /// independent view not counted): (written, read).
    pub fn rt_bytes(&self, pixels: u64) -> (u64, u64) {
        let lb = self.format.bytes_per_pixel();
        let pre = super::gbuffer::PREPASS_BYTES_PER_PIXEL;
        // pre-pass writes depth+normal; lighting reads them, writes LB; second pass reads LB +
        // depth (test), writes the HDR colour.
        (pixels * (pre + lb + 16), pixels * (pre + lb + 4))
    }
}

impl Timed for PrePass {
    /// One frame; the caller (`measure`) waits for the GPU afterwards. With CPU lighting it
    /// waits for the pre-pass's depth and normals itself, mid-frame.
    fn frame(&mut self, gpu: &Gpu, gscene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        self.run_frame(gpu, gscene, timer)?;
        Ok(FrameStats {
            geometry_passes: if self.view2.is_some() { 3 } else { 2 },
            layers: 1,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }

    /// The render-target traffic of [`PrePass::rt_bytes`] (written + read).
    fn bytes_moved(&self) -> u64 {
        let (w, r) = self.rt_bytes(self.hdr.width() as u64 * self.hdr.height() as u64);
        w + r
    }

    /// The wall-clock parts of the frame just run (CPU lighting, the wait for the pre-pass's
    /// maps, the main view's latency) and the pre-pass → material gap on the GPU clock.
    fn parts(&self, spans: &[PassSpan]) -> Vec<(Col, f64)> {
        let mut v = Vec::new();
        if let Some(f) = self.samples.last() {
            v.push((cols::LATENCY_MS, f.latency_ms));
            if matches!(self.accum, Accum::Cpu { .. }) {
                v.extend([
                    (cols::CPU_LIGHT_MS, f.cpu_light_ms),
                    (cols::MAP_WAIT_MS, f.map_wait_ms),
                    (CPU_TOTAL_MS, f.cpu_total_ms),
                    (cols::LIGHT_READY_MS, f.light_ready_ms),
                ]);
            }
        }
        if let Some((gap, busy)) = gap_of(spans) {
            v.extend([(cols::GPU_GAP_MS, gap), (cols::GPU_BUSY_IN_GAP_MS, busy)]);
        }
        v
    }
}

/// GPU clock from the end of the pre-pass to the start of the material pass, and the timed
/// pass time inside that interval (the lights pass, or the independent view's passes).
pub fn gap_of(spans: &[PassSpan]) -> Option<(f64, f64)> {
    let a = spans.iter().find(|s| s.0 == "prepass")?.2;
    let b = spans.iter().find(|s| s.0 == "material")?.1;
    let busy = spans
        .iter()
        .filter(|s| s.0 != "prepass" && s.0 != "material")
        .map(|s| (s.2.min(b) - s.1.max(a)).max(0.0))
        .sum();
    Some(((b - a).max(0.0), busy))
}

impl PrePass {
    /// One frame's work, without the wait for the GPU at its end.
    fn run_frame(&mut self, gpu: &Gpu, gscene: &GpuScene, timer: &mut GpuTimer) -> Result<()> {
        let t0 = Instant::now();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.gbuf.encode(&mut enc, gscene, timer, "prepass");
        if let AccumKind::Cpu {
            staging_depth,
            staging_normal,
            setup,
            lights,
            threads,
            overlap,
            host,
            pool,
        } = &self.kind
        {
            let (w, h) = (gscene.width, gscene.height);
            // BF3's "Z + G-buffer copy" to Cell memory, timed as its own pass (`readback`):
            // wgpu times passes only, so two empty compute passes bracket the copies, the
            // first writing the label's start, the second its end. Vulkan writes both at
            // BOTTOM_OF_PIPE (wgpu-hal), i.e. once every earlier command has finished: the
            // start follows the pre-pass, the end the copies.
            let bracket = timer.compute_pass("readback").map(|t| {
                (
                    t.query_set.clone(),
                    t.beginning_of_pass_write_index,
                    t.end_of_pass_write_index,
                )
            });
            let mark = |enc: &mut wgpu::CommandEncoder, begin: bool| {
                if let Some((set, b, e)) = &bracket {
                    enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("readback bracket"),
                        timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                            query_set: set,
                            beginning_of_pass_write_index: if begin { *b } else { None },
                            end_of_pass_write_index: if begin { None } else { *e },
                        }),
                    });
                }
            };
            mark(&mut enc, true);
            copy_to(
                &mut enc,
                &self.gbuf.depth,
                staging_depth,
                4,
                wgpu::TextureAspect::DepthOnly,
            );
            copy_to(
                &mut enc,
                &self.gbuf.normal,
                staging_normal,
                8,
                wgpu::TextureAspect::All,
            );
            mark(&mut enc, false);
            let idx = gpu.queue.submit([enc.finish()]);
            if *overlap {
                self.submit_view2(gpu, timer);
            }
            // Readiness: map_async callbacks + a blocking poll on the pre-pass submission.
            let (tx, rx) = std::sync::mpsc::channel();
            for b in [staging_depth, staging_normal] {
                let tx = tx.clone();
                b.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                    let _ = tx.send(r);
                });
            }
            gpu.device
                .poll(wgpu::PollType::Wait {
                    submission_index: Some(idx),
                    timeout: None,
                })
                .map_err(|e| CoreError::Gpu(format!("poll: {e}")))?;
            for _ in 0..2 {
                rx.recv()
                    .map_err(|_| CoreError::Gpu("map callback dropped".into()))?
                    .map_err(|e| CoreError::Gpu(format!("map: {e}")))?;
            }
            let t_ready = Instant::now();
            let gb = {
                let dm = staging_depth
                    .slice(..)
                    .get_mapped_range()
                    .map_err(|e| CoreError::Gpu(e.to_string()))?;
                let nm = staging_normal
                    .slice(..)
                    .get_mapped_range()
                    .map_err(|e| CoreError::Gpu(e.to_string()))?;
                match pool {
                    Some(p) => p.install(|| decode_prepass_par(&dm, &nm, w, h, setup.clear_depth)),
                    None => decode_prepass(&dm, &nm, w, h, setup.clear_depth),
                }
            };
            staging_depth.unmap();
            staging_normal.unmap();
            let o = CpuOptions {
                threads: *threads,
                light_buffer: true,
                parallel_reorder: *host == HostWork::Parallel,
                ..Default::default()
            };
            let (r, (bytes0, bytes1)) = match pool {
                Some(p) => p.install(|| {
                    let r = cpu_tiled::shade(setup, &gb, lights, &o);
                    let b = pack_par(self.format, &r.image);
                    (r, b)
                }),
                None => {
                    let r = cpu_tiled::shade(setup, &gb, lights, &o);
                    let b = pack(self.format, &r.image);
                    (r, b)
                }
            };
            upload(gpu, &self.lb0, &bytes0);
            if let (Some(t), Some(b)) = (&self.lb1, &bytes1) {
                upload(gpu, t, b);
            }
            let cpu_total = t_ready.elapsed().as_secs_f64() * 1e3;
            let light_ready_ms = t0.elapsed().as_secs_f64() * 1e3;
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            self.encode_second(&mut enc, gscene, timer);
            let idx3 = gpu.queue.submit([enc.finish()]);
            if !*overlap {
                self.submit_view2(gpu, timer);
            }
            gpu.device
                .poll(wgpu::PollType::Wait {
                    submission_index: Some(idx3),
                    timeout: None,
                })
                .map_err(|e| CoreError::Gpu(format!("poll: {e}")))?;
            self.samples.push(CpuFrame {
                map_wait_ms: (t_ready - t0).as_secs_f64() * 1e3,
                cpu_light_ms: r.ms,
                cpu_total_ms: cpu_total,
                latency_ms: t0.elapsed().as_secs_f64() * 1e3,
                light_ready_ms,
            });
            return Ok(());
        }
        self.encode_accum_gpu(&mut enc, timer);
        self.encode_second(&mut enc, gscene, timer);
        let idx = gpu.queue.submit([enc.finish()]);
        // The GPU-only path with the same independent view, submitted after the main view.
        self.submit_view2(gpu, timer);
        if self.view2.is_some() {
            gpu.device
                .poll(wgpu::PollType::Wait {
                    submission_index: Some(idx),
                    timeout: None,
                })
                .map_err(|e| CoreError::Gpu(format!("poll: {e}")))?;
            self.samples.push(CpuFrame {
                latency_ms: t0.elapsed().as_secs_f64() * 1e3,
                ..Default::default()
            });
        }
        Ok(())
    }
}

fn d2_bytes(d: &Deferred) -> u64 {
    d.bytes_allocated()
}

fn copy_to(
    enc: &mut wgpu::CommandEncoder,
    tex: &wgpu::Texture,
    buf: &wgpu::Buffer,
    bpp: u32,
    aspect: wgpu::TextureAspect,
) {
    let (w, h) = (tex.width(), tex.height());
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: tex,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: buf,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row(w, bpp)),
                rows_per_image: Some(h),
            },
        },
        tex.size(),
    );
}

/// Depth + f16 normal rows (padded) into a pre-pass G-buffer (sky = clear depth).
pub fn decode_prepass(depth: &[u8], normal: &[u8], w: u32, h: u32, clear: f32) -> GBuffer {
    let (rd, rn) = (padded_row(w, 4) as usize, padded_row(w, 8) as usize);
    let n = (w * h) as usize;
    let mut g = GBuffer {
        width: w,
        height: h,
        depth: Vec::with_capacity(n),
        normal: Vec::with_capacity(n),
        albedo: vec![[0.0; 3]; n],
        spec: vec![[0.0; 3]; n],
        material: Vec::with_capacity(n),
    };
    for y in 0..h as usize {
        let drow: &[f32] = bytemuck::cast_slice(&depth[y * rd..y * rd + w as usize * 4]);
        let nrow: &[u16] = bytemuck::cast_slice(&normal[y * rn..y * rn + w as usize * 8]);
        for x in 0..w as usize {
            let d = drow[x];
            g.depth.push(d);
            g.material.push(if d == clear { SKY_MATERIAL } else { 0 });
            g.normal.push(std::array::from_fn(|c| {
                half::f16::from_bits(nrow[x * 4 + c]).to_f32()
            }));
        }
    }
    g
}

/// [`decode_prepass`] by rows on the current rayon pool's threads: the same G-buffer. The
/// albedo and specular planes (the pre-pass has none) are zeroed allocations the light-buffer
/// shading never reads.
pub fn decode_prepass_par(depth: &[u8], normal: &[u8], w: u32, h: u32, clear: f32) -> GBuffer {
    use rayon::prelude::*;
    let (rd, rn) = (padded_row(w, 4) as usize, padded_row(w, 8) as usize);
    let (wu, n) = (w as usize, (w * h) as usize);
    let mut g = GBuffer {
        width: w,
        height: h,
        depth: vec![0.0; n],
        normal: vec![[0.0; 4]; n],
        albedo: vec![[0.0; 3]; n],
        spec: vec![[0.0; 3]; n],
        material: vec![0; n],
    };
    g.depth
        .par_chunks_mut(wu)
        .zip(g.normal.par_chunks_mut(wu))
        .zip(g.material.par_chunks_mut(wu))
        .enumerate()
        .for_each(|(y, ((d, nr), m))| {
            let drow: &[f32] = bytemuck::cast_slice(&depth[y * rd..y * rd + wu * 4]);
            let nrow: &[u16] = bytemuck::cast_slice(&normal[y * rn..y * rn + wu * 8]);
            d.copy_from_slice(drow);
            for x in 0..wu {
                m[x] = if drow[x] == clear { SKY_MATERIAL } else { 0 };
                nr[x] = std::array::from_fn(|c| half::f16::from_bits(nrow[x * 4 + c]).to_f32());
            }
        });
    g
}

/// [`pack`] in chunks on the current rayon pool's threads: the same bytes.
pub fn pack_par(f: LbFormat, lb: &[[f32; 4]]) -> (Vec<u8>, Option<Vec<u8>>) {
    use rayon::prelude::*;
    const CHUNK: usize = 4096;
    let s = f.scale();
    let f16 = |v: f32| half::f16::from_f32(v).to_bits().to_le_bytes();
    let bpp0 = match f {
        LbFormat::Rgba8 | LbFormat::Rg11b10 => 4,
        LbFormat::Rgba16F => 8,
    };
    let mut b0 = vec![0u8; lb.len() * bpp0];
    b0.par_chunks_mut(CHUNK * bpp0)
        .zip(lb.par_chunks(CHUNK))
        .for_each(|(out, px)| {
            for (o, p) in out.chunks_exact_mut(bpp0).zip(px) {
                match f {
                    LbFormat::Rgba8 => {
                        for c in 0..4 {
                            o[c] = ((p[c] * s).clamp(0.0, 1.0) * 255.0).round() as u8;
                        }
                    }
                    LbFormat::Rgba16F => {
                        for c in 0..4 {
                            o[2 * c..2 * c + 2].copy_from_slice(&f16(p[c] * s));
                        }
                    }
                    LbFormat::Rg11b10 => {
                        o.copy_from_slice(&pack_rg11b10([p[0], p[1], p[2]]).to_le_bytes())
                    }
                }
            }
        });
    let b1 = (f == LbFormat::Rg11b10).then(|| {
        let mut b1 = vec![0u8; lb.len() * 2];
        b1.par_chunks_mut(CHUNK * 2)
            .zip(lb.par_chunks(CHUNK))
            .for_each(|(out, px)| {
                for (o, p) in out.chunks_exact_mut(2).zip(px) {
                    o.copy_from_slice(&f16(p[3]));
                }
            });
        b1
    });
    (b0, b1)
}

/// The light buffer in its texture format(s), tightly packed rows: the first target, and the
/// second (R16F specular) for RG11B10.
pub fn pack(f: LbFormat, lb: &[[f32; 4]]) -> (Vec<u8>, Option<Vec<u8>>) {
    let s = f.scale();
    let f16 = |v: f32| half::f16::from_f32(v).to_bits().to_le_bytes();
    match f {
        LbFormat::Rgba8 => (
            lb.iter()
                .flat_map(|p| p.map(|v| ((v * s).clamp(0.0, 1.0) * 255.0).round() as u8))
                .collect(),
            None,
        ),
        LbFormat::Rgba16F => (
            lb.iter()
                .flat_map(|p| p.map(|v| f16(v * s)))
                .flatten()
                .collect(),
            None,
        ),
        LbFormat::Rg11b10 => (
            lb.iter()
                .flat_map(|p| pack_rg11b10([p[0], p[1], p[2]]).to_le_bytes())
                .collect(),
            Some(lb.iter().flat_map(|p| f16(p[3])).collect()),
        ),
    }
}

/// An unsigned float with a 5-bit exponent (bias 15) and `m` mantissa bits, rounded to nearest;
/// ≤ 0 and NaN give 0, too large the largest finite value.
pub fn to_ufloat(v: f32, m: u32) -> u32 {
    if v.is_nan() || v <= 0.0 {
        return 0;
    }
    let max = (30 << m) | ((1 << m) - 1);
    let b = v.to_bits();
    let e = ((b >> 23) & 0xff) as i32 - 127 + 15;
    if e > 30 {
        return max;
    }
    let mant = ((b & 0x7f_ffff) | 0x80_0000) as u64;
    let shift = 23 - m as i32 + if e <= 0 { 1 - e } else { 0 };
    if shift > 25 {
        return 0;
    }
    let q = ((mant + (1 << (shift - 1))) >> shift) as u32;
    let r = if e <= 0 {
        q
    } else {
        ((e as u32) << m) + q - (1 << m)
    };
    r.min(max)
}

pub fn from_ufloat(u: u32, m: u32) -> f32 {
    let (e, f) = (u >> m, u & ((1 << m) - 1));
    let frac = f as f32 / (1u32 << m) as f32;
    if e == 0 {
        frac * 2f32.powi(-14)
    } else {
        (1.0 + frac) * 2f32.powi(e as i32 - 15)
    }
}

/// R and G: 6-bit mantissas (bits 0–10, 11–21), B: 5 bits (22–31), as in the texture format.
pub fn pack_rg11b10(c: [f32; 3]) -> u32 {
    to_ufloat(c[0], 6) | (to_ufloat(c[1], 6) << 11) | (to_ufloat(c[2], 5) << 22)
}

pub fn unpack_rg11b10(p: u32) -> [f32; 3] {
    [
        from_ufloat(p & 0x7ff, 6),
        from_ufloat((p >> 11) & 0x7ff, 6),
        from_ufloat(p >> 22, 5),
    ]
}

fn upload(gpu: &Gpu, t: &wgpu::Texture, bytes: &[u8]) {
    let bpp = (bytes.len() / (t.width() * t.height()) as usize) as u32;
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: t,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(t.width() * bpp),
            rows_per_image: Some(t.height()),
        },
        t.size(),
    );
}

/// Pass label → ms of the last frame's passes (for `gpu_idle_ms`).
pub fn sum_passes(p: &[(String, f64)]) -> BTreeMap<String, f64> {
    let mut m = BTreeMap::new();
    for (l, ms) in p {
        *m.entry(l.clone()).or_insert(0.0) += ms;
    }
    m
}
