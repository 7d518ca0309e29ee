//! Moment-based order-independent transparency (Münstermann, Krumpen, Klein & Peters, I3D 2018):
//! a moments pass accumulates b₀ (total absorbance) and 4, 6 or 8 power moments or 2, 3 or 4
//! trigonometric moments of the absorbance over log-warped depth; a resolve pass reconstructs
//! each fragment's transmittance from them and accumulates its colour; a compute composite
//! applies the optional total-absorbance normalisation. Approximate (`exact() = false`): exact
//! for one layer when normalised. The rule is the CPU twin's ([`mfx_reference::oit::moments`]); the
//! reconstruction (`moment_math.wgsl`) is the twin's `moment_math` line for line, in f32.
//!
//! Axes: `moment_kind` (power | trigonometric), `moment_count` (power 4/6/8, trigonometric
//! 2/3/4; the pair is checked in `validate`), `moment_precision`: `f32` accumulates with additive
//! blending into 32-bit float targets (ordered by the API, exact up to rounding); `unorm16` is
//! the paper's 16-bit scheme (b₀-normalised, quantised moments), which needs an ordered
//! read-modify-write per fragment: wgpu has no rasterizer-ordered views, so it is an
//! **unguarded** read-modify-write of a storage buffer whose races lose updates (reported by the
//! `*_vs_k` error against the twin in arrival order; none on lavapipe, which runs a pixel's
//! fragments in order). `moment_bias`: `paper` (the paper's β for the kind, count and precision)
//! or a number; `moment_normalize` (default true).
//!
//! The warp range is the scene's view-distance span ([`mfx_reference::oit::moments::depth_range_of`],
//! from the uploaded vertex positions), passed as a uniform; `judge` runs the twin over the
//! reference fragments in arrival order with the same range, storage and bias (the method's own
//! definition, judged into `*_vs_k`).
//!
//! Memory per pixel: f32: 4 B b₀ + 4 B per moment (RGBA32F/RG32F targets) + 16 B resolve sum +
//! 16 B image; unorm16: 4 B b₀ + 2 B per moment (storage) + 16 B + 16 B.

use bytemuck::{Pod, Zeroable};

use super::shared::store::{dummy_depth, storage_pass, storage_pipeline};
use super::{Capture, Expected, FrameStats, Method, Prepared};
use bench_core::axes::{Axis, Point};
use bench_core::bind::{pipeline_layout, Bindings, Kind as B, Res, FC, FLOAT};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::{compute_pipeline, pixel_pass, read_vec, shader, STORAGE_RW};
use bench_core::record::{cols, Flag};
use bench_core::study::InvalidPoint;
use bench_core::timing::GpuTimer;
use bench_core::Result;
use mfx_reference::oit::moment_math::wrapping_zone;
use mfx_reference::oit::moments::{bias_vector, default_bias, depth_range_of, quant, B0_MIN};
use mfx_reference::oit::{self, MomentConfig, MomentKind, MomentStorage};
use mfx_reference::FragmentLists;

const WGSL: &str = include_str!("moments.wgsl");
const MATH_WGSL: &str = include_str!("moment_math.wgsl");
const B0_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
const MOMENT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const ACCUM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub struct Moments;

const KIND: Axis = Axis::choice(
    cols::MOMENT_KIND,
    "power or trigonometric moments",
    "power",
    &["power", "trigonometric"],
);
const COUNT: Axis = Axis::int(
    cols::MOMENT_COUNT,
    "moments besides b0: power 4, 6, 8; trigonometric 2, 3, 4",
    4,
    2,
    8,
);
const PRECISION: Axis = Axis::choice(
    cols::MOMENT_PRECISION,
    "f32: additive blending into 32-bit float targets; unorm16: the paper's quantised 16-bit moments by unguarded read-modify-write",
    "f32",
    &["f32", "unorm16"],
);
const BIAS: Axis = Axis::text(
    cols::MOMENT_BIAS,
    "bias β: paper (the paper's value for the kind, count and precision) or a number in [0, 1)",
    Some("paper"),
);
const NORMALIZE: Axis = Axis::bool(
    cols::MOMENT_NORMALIZE,
    "normalise the colour by the total absorbance (exact for one layer)",
    true,
);

/// What a point asks for, checked (the warp range comes at prepare).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Variant {
    kind: MomentKind,
    count: u32,
    storage: MomentStorage,
    bias: f64,
    normalize: bool,
}

fn variant(point: &Point) -> std::result::Result<Variant, InvalidPoint> {
    let kind = match point.choice(&KIND).as_str() {
        "power" => MomentKind::Power,
        _ => MomentKind::Trigonometric,
    };
    let storage = match point.choice(&PRECISION).as_str() {
        "f32" => MomentStorage::F32,
        _ => MomentStorage::Unorm16,
    };
    let count = point.int(&COUNT) as u32;
    let paper = default_bias(kind, count, storage).ok_or_else(|| {
        InvalidPoint::value(
            COUNT.name(),
            format!("{count} with moment_kind = {}", point.choice(&KIND)),
            "is not offered: power moments come in 4, 6, 8, trigonometric in 2, 3, 4",
        )
    })?;
    let text = point.choice(&BIAS);
    let bias = if text == "paper" {
        paper
    } else {
        let b: f64 = text.parse().map_err(|_| {
            InvalidPoint::value(
                BIAS.name(),
                format!("'{text}'"),
                "is neither 'paper' nor a number",
            )
        })?;
        if !(0.0..1.0).contains(&b) {
            return Err(InvalidPoint::value(BIAS.name(), b, "must lie in [0, 1)"));
        }
        b
    };
    Ok(Variant {
        kind,
        count,
        storage,
        bias,
        normalize: point.bool(&NORMALIZE),
    })
}

impl Variant {
    /// Stored reals besides b₀.
    fn reals(&self) -> u32 {
        match self.kind {
            MomentKind::Power => self.count,
            MomentKind::Trigonometric => 2 * self.count,
        }
    }
    fn unorm16(&self) -> bool {
        self.storage == MomentStorage::Unorm16
    }
    /// The twin's configuration over the warp range [near, far].
    fn config(&self, near: f64, far: f64) -> std::result::Result<MomentConfig, InvalidPoint> {
        let mut c = MomentConfig::new(self.kind, self.count, self.storage, near, far)
            .map_err(|e| InvalidPoint::Combination(e.to_string()))?;
        c.bias = self.bias;
        c.normalize = self.normalize;
        Ok(c)
    }
    /// Colour targets of the f32 moments pass: b₀, then 4 reals, then 2 or 4 more.
    fn targets(&self) -> Vec<wgpu::TextureFormat> {
        let mut t = vec![B0_FORMAT, MOMENT_FORMAT];
        match self.reals() {
            6 => t.push(wgpu::TextureFormat::Rg32Float),
            8 => t.push(MOMENT_FORMAT),
            _ => {}
        }
        t
    }
}

impl Method for Moments {
    fn name(&self) -> &'static str {
        "moments"
    }
    fn describe(&self) -> &'static str {
        "Münstermann et al. 2018 moment-based OIT: b0 + 4/6/8 power or 2/3/4 trigonometric moments (additive f32 blending, or the paper's 16-bit quantised moments by unguarded read-modify-write), resolve by moment reconstruction, optional total-absorbance normalisation; approximate (exact for one layer, normalised); 2 geometry passes + composite; 8–36 B moments + 16 B sum + 16 B image per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        vec![KIND, COUNT, PRECISION, BIAS, NORMALIZE]
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        variant(point).map(|_| ())
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        let v = variant(point)?;
        if !gpu.has(wgpu::Features::FLOAT32_BLENDABLE) {
            return Err("adapter lacks FLOAT32_BLENDABLE (additive blending into RGBA32F)".into());
        }
        let mut formats = vec![ACCUM_FORMAT];
        if !v.unorm16() {
            formats.extend(v.targets());
            let bytes: u32 = v
                .targets()
                .iter()
                .map(|f| f.block_copy_size(None).unwrap_or(16))
                .sum();
            let have = gpu.limits.max_color_attachment_bytes_per_sample;
            if bytes > have {
                return Err(format!(
                    "the moments pass writes {bytes} B per sample, {} allows {have}",
                    gpu.profile.who()
                )
                .into());
            }
        }
        for f in formats {
            if !gpu.renderable(f) {
                return Err(format!("{f:?} is not renderable on this adapter").into());
            }
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let v = variant(point)?;
        Ok(Box::new(PreparedMoments::new(gpu, scene, v)?))
    }
}

/// `struct MomentParams` of the WGSL.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    warp: [f32; 4],
    bias: [f32; 4],
    zone: [f32; 4],
    star: [f32; 8],
    quant: [[f32; 4]; 16],
    offset: [f32; 8],
}

impl Params {
    fn of(c: &MomentConfig) -> Params {
        let (near, far) = match c.warp {
            oit::Warp::Log { near, far } => (near, far),
            oit::Warp::Linear { .. } => unreachable!("the GPU build warps logarithmically"),
        };
        let mut p = Params {
            warp: [near.ln() as f32, far.ln() as f32, 0.0, 0.0],
            bias: [
                c.bias as f32,
                c.overestimation as f32,
                B0_MIN as f32,
                if c.normalize { 1.0 } else { 0.0 },
            ],
            zone: wrapping_zone(c.wrapping_zone_angle).map(|x| x as f32),
            star: [0.0; 8],
            quant: [[0.0; 4]; 16],
            offset: [0.5; 8],
        };
        if c.kind == MomentKind::Power {
            for (s, b) in p.star.iter_mut().zip(bias_vector(c.count, c.storage)) {
                *s = b as f32;
            }
            let m = c.count as usize / 2;
            let (qo, qe, dqo, dqe) = quant::matrices(m);
            for (block, mat) in [qo, qe, dqo, dqe].iter().enumerate() {
                for i in 0..m {
                    for j in 0..m {
                        p.quant[4 * block + i][j] = mat[i * m + j] as f32;
                    }
                }
            }
            for (o, x) in p.offset.iter_mut().zip(quant::offset(c.count)) {
                *o = x as f32;
            }
        }
        p
    }
}

struct PreparedMoments {
    cfg: MomentConfig,
    unorm16: bool,
    moments: wgpu::RenderPipeline,
    resolve: wgpu::RenderPipeline,
    composite: wgpu::ComputePipeline,
    bind_moments: wgpu::BindGroup,
    bind_resolve: wgpu::BindGroup,
    bind_composite: wgpu::BindGroup,
    /// f32: the moment targets (b₀ first).
    targets: Vec<wgpu::TextureView>,
    accum: wgpu::TextureView,
    store16: wgpu::Buffer,
    depth: Option<wgpu::TextureView>,
    image: wgpu::Buffer,
    /// Fragments whose transmittance reconstruction failed this frame.
    failures: wgpu::Buffer,
    alloc: AllocCounter,
}

/// The scene's warp range, from the uploaded positions (as `oit::moments::depth_range`).
fn warp_range(gpu: &Gpu, scene: &GpuScene) -> Result<(f64, f64)> {
    let n = (scene.positions.size() / 12) as usize;
    let pos = read_vec::<[f32; 3]>(gpu, &scene.positions, n)?;
    let view = glam::Mat4::from_cols_array_2d(&scene.camera_data.view_from_world);
    let nf = scene.camera_data.near_far;
    Ok(depth_range_of(&pos, view, nf[0] as f64, nf[1] as f64))
}

fn add_blend(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    let add = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    Some(wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState {
            color: add,
            alpha: add,
        }),
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A raster pipeline over `vs_full`, both faces, no depth test, additive into `targets`.
fn blend_pipeline(
    gpu: &Gpu,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    fs: &str,
    constants: &[(&str, f64)],
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    super::shared::store::full_pipeline(gpu, label, layout, module, fs, constants, targets, None)
}

/// The overrides every moments stage shares: the basis, the moment count, the stored reals
/// and the 16-bit store.
fn variant_constants(v: &Variant) -> [(&'static str, f64); 4] {
    let kind = if v.kind == MomentKind::Power {
        0.0
    } else {
        1.0
    };
    [
        ("KIND", kind),
        ("COUNT", v.count as f64),
        ("REALS", v.reals() as f64),
        ("UNORM16", if v.unorm16() { 1.0 } else { 0.0 }),
    ]
}

impl PreparedMoments {
    fn new(gpu: &Gpu, scene: &GpuScene, v: Variant) -> Result<Self> {
        let d = &gpu.device;
        let (near, far) = warp_range(gpu, scene)?;
        let cfg = v.config(near, far)?;
        let module = shader(gpu, "moments", &format!("{WGSL}\n{MATH_WGSL}"));
        let constants = variant_constants(&v);
        // Camera, parameters, the 16-bit store; the resolve adds b0, m0, m1 and the failure
        // count, the composite b0, the resolve sum and the image. One table per pass: a
        // texture cannot be a pass's target and bound in it at once.
        let base = [(0, B::Camera), (1, B::Uniform), (2, B::Storage)];
        let table = |label: &str, extra: &[(u32, B)]| {
            let mut rows = base.to_vec();
            rows.extend_from_slice(extra);
            Bindings::new(gpu, label, FC, &rows)
        };
        let tex = B::Texture(FLOAT);
        let bgl_moments = table("moments: moments pass", &[]);
        let resolve_rows = [(3, tex), (4, tex), (5, tex), (8, B::Storage)];
        let bgl_resolve = table("moments: resolve pass", &resolve_rows);
        let bgl_composite = table("moments: composite", &[(3, tex), (6, tex), (7, B::Storage)]);
        let layout = |t: &Bindings| pipeline_layout(gpu, "moments", &[&t.layout]);
        let mut alloc = AllocCounter::default();
        let (w, h) = (scene.width, scene.height);
        let px = scene.pixels() as u64;
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let stand_in = |alloc: &mut AllocCounter, label: &str, f| {
            alloc
                .texture(gpu, label, 1, 1, f, wgpu::TextureUsages::TEXTURE_BINDING)
                .create_view(&Default::default())
        };
        let (moments, targets, store16, depth) = if v.unorm16() {
            let words = 1 + v.reals() as u64 / 2;
            let store16 = alloc.buffer(gpu, "moments 16-bit store", px * words * 4, STORAGE_RW);
            let p = storage_pipeline(
                gpu,
                "moments: 16-bit moments",
                &layout(&bgl_moments),
                &module,
                "fs_moments16",
                &constants,
            );
            let depth = dummy_depth(gpu, &mut alloc, scene);
            (p, Vec::new(), store16, Some(depth))
        } else {
            let formats = v.targets();
            let views: Vec<wgpu::TextureView> = formats
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    alloc
                        .texture(gpu, &format!("moments target {i}"), w, h, *f, usage)
                        .create_view(&Default::default())
                })
                .collect();
            let states: Vec<_> = formats.iter().map(|f| add_blend(*f)).collect();
            let fs = if formats.len() == 2 {
                "fs_moments2"
            } else {
                "fs_moments3"
            };
            let p = blend_pipeline(
                gpu,
                "moments: moments pass",
                &layout(&bgl_moments),
                &module,
                fs,
                &constants,
                &states,
            );
            let store16 = alloc.buffer(gpu, "moments store (unused)", 16, STORAGE_RW);
            (p, views, store16, None)
        };
        let resolve = blend_pipeline(
            gpu,
            "moments: resolve pass",
            &layout(&bgl_resolve),
            &module,
            "fs_resolve",
            &constants,
            &[add_blend(ACCUM_FORMAT)],
        );
        let composite = compute_pipeline(
            gpu,
            "moments: composite",
            &layout(&bgl_composite),
            &module,
            "composite",
            &constants,
            false,
        );
        let accum = alloc
            .texture(gpu, "moments resolve sum", w, h, ACCUM_FORMAT, usage)
            .create_view(&Default::default());
        let image = alloc.buffer(gpu, "moments image", px * 16, STORAGE_RW);
        let failures = alloc.buffer(gpu, "moments reconstruction failures", 4, STORAGE_RW);
        let params = Params::of(&cfg);
        let params_buf = {
            use wgpu::util::DeviceExt;
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("moments params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            })
        };
        let (b0_view, m0_view, m1_view) = if v.unorm16() {
            (
                stand_in(&mut alloc, "moments b0 (unused)", B0_FORMAT),
                stand_in(&mut alloc, "moments m0 (unused)", MOMENT_FORMAT),
                stand_in(&mut alloc, "moments m1 (unused)", MOMENT_FORMAT),
            )
        } else {
            let m1 = match targets.get(2) {
                Some(t) => t.clone(),
                None => stand_in(&mut alloc, "moments m1 (unused)", MOMENT_FORMAT),
            };
            (targets[0].clone(), targets[1].clone(), m1)
        };
        let base_res = [&scene.camera, &params_buf, &store16].map(Res::Buf);
        let group = |t: &Bindings, extra: &[Res]| {
            let mut res = base_res.to_vec();
            res.extend_from_slice(extra);
            t.group(gpu, &res)
        };
        let bind_moments = group(&bgl_moments, &[]);
        let (b0, m0, m1) = (
            Res::View(&b0_view),
            Res::View(&m0_view),
            Res::View(&m1_view),
        );
        let bind_resolve = group(&bgl_resolve, &[b0, m0, m1, (&failures).into()]);
        let bind_composite = group(&bgl_composite, &[b0, (&accum).into(), (&image).into()]);
        Ok(PreparedMoments {
            cfg,
            unorm16: v.unorm16(),
            moments,
            resolve,
            composite,
            bind_moments,
            bind_resolve,
            bind_composite,
            targets,
            accum,
            store16,
            depth,
            image,
            failures,
            alloc,
        })
    }
}

impl bench_core::timed::Timed for PreparedMoments {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        let zero = wgpu::Color::TRANSPARENT;
        enc.clear_buffer(&self.failures, 0, None);
        if let Some(depth) = &self.depth {
            enc.clear_buffer(&self.store16, 0, None);
            let mut pass = storage_pass(&mut enc, depth, timer, "moments");
            pass.set_pipeline(&self.moments);
            pass.set_bind_group(0, &self.bind_moments, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        } else {
            let atts: Vec<_> = self
                .targets
                .iter()
                .map(|t| bench_core::gpu::cleared(t, zero))
                .collect();
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("moments"),
                color_attachments: &atts,
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("moments"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.moments);
            pass.set_bind_group(0, &self.bind_moments, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("resolve"),
                color_attachments: &[bench_core::gpu::cleared(&self.accum, zero)],
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("resolve"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.resolve);
            pass.set_bind_group(0, &self.bind_resolve, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        pixel_pass(
            &mut enc,
            timer,
            "composite",
            &self.composite,
            &self.bind_composite,
            scene,
        );
        gpu.queue.submit([enc.finish()]);
        Ok(FrameStats {
            geometry_passes: 2,
            layers: 0,
        })
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl Prepared for PreparedMoments {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, scene.pixels())?);
        cap.expected = Expected::All;
        let failed = read_vec::<u32>(gpu, &self.failures, 1)?[0];
        if failed > 0 {
            cap.flag.add(Flag::Precision);
        }
        let (near, far) = match self.cfg.warp {
            oit::Warp::Log { near, far } => (near, far),
            oit::Warp::Linear { near, far } => (near, far),
        };
        cap.notes = format!(
            "approximate: {:?} {} moments, bias {:e}, log warp over view distance [{near:.4}, {far:.4}]{}; {failed} fragments' transmittance reconstruction failed in f32 (resolved as T = 0, as the paper's saturate does){}",
            self.cfg.kind,
            self.cfg.count,
            self.cfg.bias,
            if self.cfg.normalize { ", normalised" } else { "" },
            if self.unorm16 {
                "; 16-bit moments by unguarded read-modify-write (no rasterizer-ordered views): races lose updates"
            } else {
                ""
            }
        );
        Ok(cap)
    }

    /// The twin in arrival (primitive) order with the same storage, warp and bias: what the
    /// method gives without races and in f64 arithmetic.
    fn judge(&mut self, cap: &mut Capture, reference: &FragmentLists) {
        let cfg = self.cfg;
        cap.definition = Some(oit::image(reference, true, |l| oit::moments(l, &cfg)));
    }
}

#[cfg(test)]
mod tests;
