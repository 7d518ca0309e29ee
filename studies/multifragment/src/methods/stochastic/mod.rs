//! Stochastic transparency (Enderton, Sintorn, Shirley & Luebke, "Stochastic Transparency",
//! I3D 2010 / TVCG 2011; the far end of Wyman's continuum, HPG 2016): transparency as coverage.
//! Each fragment keeps a random ⌊α·S + ξ⌋ of its S MSAA samples (seeded, the same every frame)
//! in a depth-only pass; a second pass adds every fragment's premultiplied colour to the samples
//! where nothing nearer kept them; the sample mean is an unbiased estimate of the under-
//! composite. `st_passes` independent passes are averaged (S × passes samples in all). With
//! `st_correction` an extra pass blends the exact total alpha per sample and the colour is
//! rescaled to it (the paper's alpha correction: less noise, a small bias).
//!
//! Approximate (`exact() = false`); judged against the multisampled ground truth of S samples
//! (the geometric antialiasing it does is S× MSAA): `Capture.aa = msaa<S>`. Memory per pixel:
//! S × (4 B depth + 16 B RGBA32F sum + 4 B R32F revealage with the correction) + 16 B running
//! sum + 16 B image. Transparency only (no fold: it never has the fragments in order).

use super::{Capture, Expected, FrameStats, Method, Prepared};
use crate::aa::{self, AaMode};
use bench_core::axes::{Axis, Point};
use bench_core::bind::{
    blended, pipeline_layout, render_pipeline, Bindings, Kind as B, Raster, ADD, FLOAT, TRANSMIT,
};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::{clear_depth, compute_pipeline, read_vec, shader, STORAGE_RW};
use bench_core::record::cols;
use bench_core::study::InvalidPoint;
use bench_core::timing::GpuTimer;
use bench_core::Result;

const WGSL: &str = include_str!("stochastic.wgsl");
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const ACCUM: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const REVEAL: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

pub struct Stochastic;

pub const ST_SAMPLES: Axis = Axis::int(
    cols::ST_SAMPLES,
    "MSAA samples per pass S (2, 4 or 8)",
    4,
    2,
    8,
);
pub const ST_PASSES: Axis = Axis::int(
    cols::ST_PASSES,
    "independent passes averaged (S × passes samples in all)",
    1,
    1,
    256,
);
pub const ST_CORRECTION: Axis = Axis::bool(
    cols::ST_CORRECTION,
    "alpha correction: colour rescaled to the exact total alpha (one more geometry pass)",
    true,
);
pub const ST_SEED: Axis = Axis::int(
    cols::ST_SEED,
    "seed of the per-fragment sample masks",
    1,
    0,
    u32::MAX as i64,
);

#[derive(Clone, Copy, Debug)]
struct Config {
    samples: u32,
    passes: u32,
    correction: bool,
    seed: u32,
}

impl Config {
    fn read(point: &Point) -> Config {
        Config {
            samples: point.int(&ST_SAMPLES) as u32,
            passes: point.int(&ST_PASSES) as u32,
            correction: point.bool(&ST_CORRECTION),
            seed: point.int(&ST_SEED) as u32,
        }
    }
}

impl Method for Stochastic {
    fn name(&self) -> &'static str {
        "stochastic"
    }
    fn describe(&self) -> &'static str {
        "Enderton et al. 2010 stochastic transparency: random α·S-sample masks depth-tested per MSAA sample, colour accumulated where visible, passes averaged, optional alpha correction; approximate (unbiased without correction); 2 geometry passes per pass (+1 for the correction); S × 20–24 B + 32 B per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        vec![ST_SAMPLES, ST_PASSES, ST_CORRECTION, ST_SEED]
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        let s = point.int(&ST_SAMPLES);
        if ![2, 4, 8].contains(&s) {
            return Err(InvalidPoint::value(
                ST_SAMPLES.name(),
                s,
                "must be 2, 4 or 8 (an MSAA count)",
            ));
        }
        Ok(())
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        let cfg = Config::read(point);
        if !gpu.has(wgpu::Features::FLOAT32_BLENDABLE) {
            return Err("the RGBA32F sums need FLOAT32_BLENDABLE".into());
        }
        for f in [DEPTH, ACCUM, REVEAL] {
            aa::check_msaa_format(gpu, f, cfg.samples)?;
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        self.validate(point)?;
        Ok(Box::new(PreparedSt::new(gpu, scene, Config::read(point))))
    }
}

struct PreparedSt {
    depth_pass: wgpu::RenderPipeline,
    accum_pass: wgpu::RenderPipeline,
    alpha_pass: wgpu::RenderPipeline,
    resolve_pass: wgpu::ComputePipeline,
    finish: wgpu::ComputePipeline,
    raster_bind: wgpu::BindGroup,
    compute_bind: wgpu::BindGroup,
    depth: wgpu::TextureView,
    accum: wgpu::TextureView,
    reveal: wgpu::TextureView,
    sum: wgpu::Buffer,
    image: wgpu::Buffer,
    cfg: Config,
    reversed: bool,
    sample_positions: String,
    alloc: AllocCounter,
    overhead: u64,
}

const ATTRS: Attrs = Attrs {
    normal: false,
    color: true,
    object_id: false,
};

impl PreparedSt {
    fn new(gpu: &Gpu, scene: &GpuScene, cfg: Config) -> Self {
        let d = &gpu.device;
        let s = cfg.samples;
        let module = shader(gpu, "stochastic", WGSL);
        let cs = wgpu::ShaderStages::COMPUTE;
        let vfc = wgpu::ShaderStages::VERTEX_FRAGMENT | cs;
        // Camera and the pass parameters (seed, passes, correction); the resolve adds the
        // samples' sums and revealage, the running sum and the image.
        let raster_table = Bindings::seq(gpu, "stochastic raster", vfc, &[B::Camera, B::Uniform]);
        let ms = B::TextureMs(FLOAT);
        let rows = [B::Camera, B::Uniform, ms, ms, B::Storage, B::Storage];
        let compute_table = Bindings::seq(gpu, "stochastic resolve", cs, &rows);
        let raster_layout = pipeline_layout(gpu, "stochastic", &[&raster_table.layout]);
        let compute_layout = pipeline_layout(gpu, "stochastic", &[&compute_table.layout]);
        let constants = [("SAMPLES", s as f64)];
        let buffers: Vec<_> = GpuScene::layouts(ATTRS).into_iter().map(Some).collect();
        // Nearest sample depth first (written), then every fragment at or before it.
        let (nearer, nearer_or_equal) = if scene.reversed_z {
            use wgpu::CompareFunction::{Greater, GreaterEqual};
            (Greater, GreaterEqual)
        } else {
            use wgpu::CompareFunction::{Less, LessEqual};
            (Less, LessEqual)
        };
        let depth_state = |compare, write| wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        };
        let pipeline = |label: &str,
                        fs: &str,
                        depth: Option<wgpu::DepthStencilState>,
                        targets: &[Option<wgpu::ColorTargetState>]| {
            let r = Raster {
                module: &module,
                vs: "vs_st",
                buffers: &buffers,
                fs,
                targets,
                constants: &constants,
                depth,
                samples: s,
            };
            render_pipeline(gpu, label, &raster_layout, r)
        };
        let depth_pass = pipeline(
            "stochastic depth",
            "fs_depth",
            Some(depth_state(nearer, true)),
            &[],
        );
        let accum_pass = pipeline(
            "stochastic accumulate",
            "fs_accum",
            Some(depth_state(nearer_or_equal, false)),
            &[blended(ACCUM, ADD)],
        );
        let alpha_pass = pipeline(
            "stochastic total alpha",
            "fs_alpha",
            None,
            &[blended(REVEAL, TRANSMIT)],
        );
        let resolve_pass = compute_pipeline(
            gpu,
            "stochastic resolve",
            &compute_layout,
            &module,
            "resolve_pass",
            &constants,
            false,
        );
        let finish = compute_pipeline(
            gpu,
            "stochastic finish",
            &compute_layout,
            &module,
            "finish",
            &constants,
            false,
        );

        let mut alloc = AllocCounter::default();
        let (w, h) = (scene.width, scene.height);
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let ra = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let depth = alloc
            .texture_ms(gpu, "stochastic depth", w, h, DEPTH, ra, s)
            .create_view(&Default::default());
        let accum = alloc
            .texture_ms(gpu, "stochastic sums", w, h, ACCUM, usage, s)
            .create_view(&Default::default());
        // Without the correction the revealage is never drawn: a 1×1 stand-in.
        let (rw, rh) = if cfg.correction { (w, h) } else { (1, 1) };
        let reveal = alloc
            .texture_ms(gpu, "stochastic revealage", rw, rh, REVEAL, usage, s)
            .create_view(&Default::default());
        let px = scene.pixels() as u64;
        let sum = alloc.buffer(gpu, "stochastic running sum", px * 16, STORAGE_RW);
        let image = alloc.buffer(gpu, "stochastic image", px * 16, STORAGE_RW);
        let params = wgpu::util::DeviceExt::create_buffer_init(
            d,
            &wgpu::util::BufferInitDescriptor {
                label: Some("stochastic params"),
                contents: bytemuck::cast_slice(&[cfg.seed, cfg.passes, cfg.correction as u32, 0]),
                usage: wgpu::BufferUsages::UNIFORM,
            },
        );
        let raster_bind = raster_table.group(gpu, &[(&scene.camera).into(), (&params).into()]);
        let compute_bind = compute_table.group(
            gpu,
            &[
                (&scene.camera).into(),
                (&params).into(),
                (&accum).into(),
                (&reveal).into(),
                (&sum).into(),
                (&image).into(),
            ],
        );
        // Everything is per pixel: the samples' targets, the running sum and the image.
        let overhead = alloc.bytes;
        PreparedSt {
            depth_pass,
            accum_pass,
            alpha_pass,
            resolve_pass,
            finish,
            raster_bind,
            compute_bind,
            depth,
            accum,
            reveal,
            sum,
            image,
            cfg,
            reversed: scene.reversed_z,
            sample_positions: aa::sample_positions(gpu, s),
            alloc,
            overhead,
        }
    }

    /// Draws every triangle as instance `pass` (the shaders' pass index).
    fn draw(&self, pass: &mut wgpu::RenderPass<'_>, scene: &GpuScene, index: u32) {
        pass.set_bind_group(0, &self.raster_bind, &[]);
        pass.set_vertex_buffer(0, scene.positions.slice(..));
        pass.set_vertex_buffer(1, scene.colors.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..scene.index_count, 0, index..index + 1);
    }

    fn compute(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        label: &str,
        p: &wgpu::ComputePipeline,
    ) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: timer.compute_pass(label),
        });
        pass.set_pipeline(p);
        pass.set_bind_group(0, &self.compute_bind, &[]);
        pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
    }
}

impl bench_core::timed::Timed for PreparedSt {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.sum, 0, None);
        let mut stats = FrameStats::default();
        if self.cfg.correction {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("total alpha"),
                color_attachments: &[bench_core::gpu::cleared(&self.reveal, wgpu::Color::WHITE)],
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("total_alpha"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.alpha_pass);
            self.draw(&mut pass, scene, 0);
            stats.geometry_passes += 1;
        }
        for p in 0..self.cfg.passes {
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("stochastic depth"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &self.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(clear_depth(self.reversed)),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: timer.render_pass("stochastic_depth"),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.depth_pass);
                self.draw(&mut pass, scene, p);
            }
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("stochastic accumulate"),
                    color_attachments: &[bench_core::gpu::cleared(
                        &self.accum,
                        wgpu::Color::TRANSPARENT,
                    )],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &self.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Discard,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: timer.render_pass("accumulate"),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.accum_pass);
                self.draw(&mut pass, scene, p);
            }
            self.compute(&mut enc, scene, timer, "resolve", &self.resolve_pass);
            stats.geometry_passes += 2;
            stats.layers += 1;
        }
        self.compute(&mut enc, scene, timer, "finish", &self.finish);
        gpu.queue.submit([enc.finish()]);
        Ok(stats)
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }

    fn bytes_overhead(&self) -> Option<u64> {
        Some(self.overhead)
    }
}

impl Prepared for PreparedSt {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, scene.pixels())?);
        cap.expected = Expected::All;
        cap.aa = Some(AaMode::Msaa(self.cfg.samples));
        cap.sample_positions = Some(self.sample_positions.clone());
        cap.notes = format!(
            "stochastic: {} samples per pass × {} passes = {} samples per pixel, seed {}{}",
            self.cfg.samples,
            self.cfg.passes,
            self.cfg.samples * self.cfg.passes,
            self.cfg.seed,
            if self.cfg.correction {
                ", alpha-corrected"
            } else {
                ", uncorrected (unbiased)"
            }
        );
        Ok(cap)
    }

    fn image_buffer(&self) -> Option<&wgpu::Buffer> {
        Some(&self.image)
    }
}

#[cfg(test)]
mod tests;
