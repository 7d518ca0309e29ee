//! The G-buffer pass of the shading studies: depth (Depth32Float), view-space normal +
//! smoothness (Rgba16Float), albedo (Rgba8Unorm), specular colour (Rgba8Unorm) and material id
//! (R32Uint, [`SKY_MATERIAL`] where nothing was drawn: the sky mark) — 24 bytes per pixel. The
//! light pre-pass variant writes only depth and normal + smoothness (12 bytes per pixel).
//! Also the read-back helpers that decode it for the f64 reference and the CPU tile path.

use bench_core::gpu_util::{camera_entry, clear_depth, depth_state, shader, storage_entry};
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::{GBuffer, SKY_MATERIAL};
use bench_core::gpu::Gpu;
pub use bench_core::gpu::{padded_row, read_rgba32f, read_texture};
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};

use bench_core::timing::GpuTimer;
use bench_core::Result;

const WGSL: &str = include_str!("gbuffer.wgsl");

pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const SPEC_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const MAT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Bytes per pixel written by the full G-buffer pass (depth + 4 targets).
pub const FULL_BYTES_PER_PIXEL: u64 = 4 + 8 + 4 + 4 + 4;
/// Bytes per pixel written by the light pre-pass's geometry pass (depth + normal).
pub const PREPASS_BYTES_PER_PIXEL: u64 = 4 + 8;

/// Matches `struct Material` in gbuffer.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct GpuMaterial {
    pub albedo_smooth: [f32; 4],
    pub spec: [f32; 4],
}

/// The materials of a scene by object id (the default material where the scene has none).
pub fn materials(scene: &scenarios::Scene) -> Vec<GpuMaterial> {
    let n = scene
        .mesh
        .object_ids
        .iter()
        .max()
        .map(|m| *m as usize + 1)
        .unwrap_or(1)
        .max(scene.materials.len());
    (0..n)
        .map(|i| {
            let m = scene.materials.get(i).copied().unwrap_or_default();
            GpuMaterial {
                albedo_smooth: [m.albedo[0], m.albedo[1], m.albedo[2], m.smoothness],
                spec: [m.specular[0], m.specular[1], m.specular[2], 0.0],
            }
        })
        .collect()
}

/// The G-buffer targets and the pipeline that fills them.
pub struct GBufferPass {
    pub depth: wgpu::Texture,
    pub normal: wgpu::Texture,
    pub albedo: Option<wgpu::Texture>,
    pub spec: Option<wgpu::Texture>,
    pub mat: Option<wgpu::Texture>,
    pub depth_view: wgpu::TextureView,
    pipeline: wgpu::RenderPipeline,
    bind0: wgpu::BindGroup,
    bind1: wgpu::BindGroup,
    pub materials: wgpu::Buffer,
    reversed: bool,
    /// True: depth + normal only (light pre-pass).
    pub prepass: bool,
    /// Samples per pixel (2: the MSAA G-buffer of `msaa = x2`, read back by `msaa::read_samples`).
    pub samples: u32,
}

impl GBufferPass {
    pub fn new(
        gpu: &Gpu,
        scene: &scenarios::Scene,
        gscene: &GpuScene,
        prepass: bool,
        alloc: &mut AllocCounter,
    ) -> GBufferPass {
        Self::new_ms(gpu, scene, gscene, prepass, 1, alloc)
    }

    /// [`GBufferPass::new`] with `samples` samples per pixel (> 1: multisampled targets, the
    /// full G-buffer only; its fragment shader also writes the pixel-centre depth, so every
    /// sample a triangle covers holds the same values: `msaa.rs`).
    pub fn new_ms(
        gpu: &Gpu,
        scene: &scenarios::Scene,
        gscene: &GpuScene,
        prepass: bool,
        samples: u32,
        alloc: &mut AllocCounter,
    ) -> GBufferPass {
        assert!(samples == 1 || !prepass, "the MSAA G-buffer is a full one");
        let d = &gpu.device;
        let (w, h) = (gscene.width, gscene.height);
        let module = shader(gpu, "gbuffer", WGSL);
        let bgl0 = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer camera"),
            entries: &[camera_entry(0)],
        });
        let bgl1 = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gbuffer materials"),
            entries: &[storage_entry(0, true, wgpu::ShaderStages::FRAGMENT)],
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer"),
            bind_group_layouts: &[Some(&bgl0), Some(&bgl1)],
            immediate_size: 0,
        });
        let mats = materials(scene);
        let materials = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("materials"),
            contents: bytemuck::cast_slice(&mats),
            usage: wgpu::BufferUsages::STORAGE,
        });
        alloc.bytes += materials.size();
        let bind0 = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer camera"),
            layout: &bgl0,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: gscene.camera.as_entire_binding(),
            }],
        });
        let bind1 = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer materials"),
            layout: &bgl1,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: materials.as_entire_binding(),
            }],
        });
        // Multisampled textures cannot be copied: no COPY_SRC (read back by a compute pass).
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | if samples == 1 {
                wgpu::TextureUsages::COPY_SRC
            } else {
                wgpu::TextureUsages::empty()
            };
        let mut tex = |label, format| alloc.texture_ms(gpu, label, w, h, format, usage, samples);
        let depth = tex("gb depth", wgpu::TextureFormat::Depth32Float);
        let normal = tex("gb normal", NORMAL_FORMAT);
        let (albedo, spec, mat) = if prepass {
            (None, None, None)
        } else {
            (
                Some(tex("gb albedo", ALBEDO_FORMAT)),
                Some(tex("gb spec", SPEC_FORMAT)),
                Some(tex("gb material", MAT_FORMAT)),
            )
        };
        let target = |f| {
            Some(wgpu::ColorTargetState {
                format: f,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let targets: Vec<Option<wgpu::ColorTargetState>> = if prepass {
            vec![target(NORMAL_FORMAT)]
        } else {
            vec![
                target(NORMAL_FORMAT),
                target(ALBEDO_FORMAT),
                target(SPEC_FORMAT),
                target(MAT_FORMAT),
            ]
        };
        let attrs = Attrs::ALL;
        let layouts = GpuScene::layouts(attrs);
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("gbuffer"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_full"),
                compilation_options: Default::default(),
                buffers: &layouts.iter().map(|l| Some(l.clone())).collect::<Vec<_>>(),
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(depth_state(gscene.reversed_z, true)),
            multisample: wgpu::MultisampleState {
                count: samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(match (prepass, samples > 1) {
                    (true, _) => "fs_prepass",
                    (false, false) => "fs_gbuffer",
                    (false, true) => "fs_gbuffer_ms",
                }),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let depth_view = depth.create_view(&Default::default());
        GBufferPass {
            depth,
            normal,
            albedo,
            spec,
            mat,
            depth_view,
            pipeline,
            bind0,
            bind1,
            materials,
            reversed: gscene.reversed_z,
            prepass,
            samples,
        }
    }

    /// Encodes the geometry pass (timed as `label`).
    pub fn encode(
        &self,
        enc: &mut wgpu::CommandEncoder,
        gscene: &GpuScene,
        timer: &mut GpuTimer,
        label: &str,
    ) {
        let views: Vec<wgpu::TextureView> = [
            Some(&self.normal),
            self.albedo.as_ref(),
            self.spec.as_ref(),
            self.mat.as_ref(),
        ]
        .into_iter()
        .flatten()
        .map(|t| t.create_view(&Default::default()))
        .collect();
        let att: Vec<Option<wgpu::RenderPassColorAttachment>> = views
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let clear = if i == 3 {
                    wgpu::Color {
                        r: SKY_MATERIAL as f64,
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    }
                } else {
                    wgpu::Color::TRANSPARENT
                };
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &att,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear_depth(self.reversed)),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.render_pass(label),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind0, &[]);
        pass.set_bind_group(1, &self.bind1, &[]);
        gscene.draw(&mut pass, Attrs::ALL);
    }

    /// Reads the G-buffer back and decodes it. For the pre-pass variant, albedo/spec come from
    /// the material table (`mats`, by object id) is not possible (no id target): they are zero
    /// and the material is 0 except where the depth is the clear value (sky).
    /// Single-sample only: multisampled textures cannot be copied, so a multisampled G-buffer
    /// is read by `msaa::read_samples` (which calls this for one sample; this module does not
    /// call it back).
    pub fn read(&self, gpu: &Gpu) -> Result<GBuffer> {
        if self.samples > 1 {
            return Err(bench_core::CoreError::Param(format!(
                "a {}-sample G-buffer is read by msaa::read_samples",
                self.samples
            )));
        }
        let (w, h) = (self.depth.width(), self.depth.height());
        let n = (w * h) as usize;
        let depth: Vec<f32> = bytemuck::cast_slice(&read_texture(
            gpu,
            &self.depth,
            4,
            wgpu::TextureAspect::DepthOnly,
        )?)
        .to_vec();
        let nb = read_texture(gpu, &self.normal, 8, wgpu::TextureAspect::All)?;
        let halves: &[u16] = bytemuck::cast_slice(&nb);
        let normal: Vec<[f32; 4]> = (0..n)
            .map(|i| std::array::from_fn(|c| half::f16::from_bits(halves[i * 4 + c]).to_f32()))
            .collect();
        let unorm = |t: &Option<wgpu::Texture>| -> Result<Vec<[f32; 3]>> {
            Ok(match t {
                Some(t) => {
                    let b = read_texture(gpu, t, 4, wgpu::TextureAspect::All)?;
                    (0..n)
                        .map(|i| std::array::from_fn(|c| b[i * 4 + c] as f32 / 255.0))
                        .collect()
                }
                None => vec![[0.0; 3]; n],
            })
        };
        let albedo = unorm(&self.albedo)?;
        let spec = unorm(&self.spec)?;
        let clear = clear_depth(self.reversed);
        let material: Vec<u32> = match &self.mat {
            Some(t) => {
                bytemuck::cast_slice(&read_texture(gpu, t, 4, wgpu::TextureAspect::All)?).to_vec()
            }
            None => depth
                .iter()
                .map(|&d| if d == clear { SKY_MATERIAL } else { 0 })
                .collect(),
        };
        Ok(GBuffer {
            width: w,
            height: h,
            depth,
            normal,
            albedo,
            spec,
            material,
        })
    }
}
