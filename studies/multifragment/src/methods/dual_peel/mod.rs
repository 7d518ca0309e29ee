//! Dual depth peeling (Bavoil & Myers 2008, "Order Independent Transparency with Dual Depth
//! Peeling"): MAX blending on a RG32F target keeps the nearest and farthest unpeeled depth per
//! pixel, so each geometry pass peels two layers: the nearest is composited under a front
//! accumulation, the farthest over a back accumulation, and one final pass combines them.
//! ⌈n/2⌉ + 1 geometry passes for n layers. Needs FLOAT32_BLENDABLE (skipped without it).
//! Axes like `depth_peel`: `max_layers` (⌈max_layers/2⌉ peel passes at most; pixels left with
//! fragments are counted as `overflow_pixels`) and `occlusion_stop` (a count of pixels with
//! fragments left, read by the CPU after each pass, ends peeling when it reaches 0; otherwise
//! exactly ⌈max_layers/2⌉ peel passes in one submission). Exact except coplanar ties.
//!
//! Effects: transparency on colour layers; translucency and Fresnel (Bavoil's thesis §6.1 reads
//! no more than depth, facing and a normal) on layers of (signed view depth, normal), folded by
//! two effects fold states per pixel, one fed nearest first and one farthest first, combined
//! once (their thickness sums and transmittance products compose; see `dual_peel.wgsl`). CSG
//! and depth of field are skipped with the reason ([`effect_of`]).

use super::shared::axes::{MAX_LAYERS, OCCLUSION_STOP};
use super::{Capture, Expected, FrameStats, Method, Prepared};
use crate::effects::{self, Effect, EffectConfig, Payload, FOLD_STATE_BYTES, FOLD_WGSL};
use bench_core::axes::{Axis, Point};
use bench_core::bind::{
    blended, pipeline_layout, render_pipeline, Bindings, Kind as B, Raster, Res, FLOAT,
};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::gpu_util::{compute_pipeline, read_vec, shader, STORAGE_RW};
use bench_core::record::Flag;
use bench_core::study::InvalidPoint;
use bench_core::timing::GpuTimer;
use bench_core::Result;

const WGSL: &str = include_str!("dual_peel.wgsl");
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
const LAYER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// The "nothing here" value of the MAX-blended depth target (−BIG in the WGSL).
const BIG: f64 = 3.0e38;

pub struct DualPeel;

/// The point's effect, or why dual peeling cannot fold it: csg's first-surface search and dof's
/// nearest-per-partition both need what the front sweep has not yet seen when the back sweep
/// meets it (csg: the inside/outside state; dof: colour beside the depth, 5 channels in a
/// 4-channel layer).
fn effect_of(point: &Point) -> std::result::Result<EffectConfig, InvalidPoint> {
    let e = EffectConfig::from_point(point)?;
    match e.effect {
        Effect::Transparency | Effect::Translucency | Effect::Fresnel => Ok(e),
        other => Err(InvalidPoint::combination(format!(
            "dual_peel folds transparency, translucency and fresnel (they compose from a front and a back sweep): {} needs the front sweep's state or colour beside the depth at the back sweep's layer, which a 4-channel layer and two accumulations cannot keep",
            other.name()
        ))),
    }
}

/// Whether the layers hold (signed view depth, normal) for the effects fold.
fn fx(e: &EffectConfig) -> bool {
    e.effect != Effect::Transparency
}

impl Method for DualPeel {
    fn name(&self) -> &'static str {
        "dual_peel"
    }
    fn describe(&self) -> &'static str {
        "Bavoil & Myers 2008: dual depth peeling (RG32F MAX blending), exact up to max_layers; ⌈n/2⌉+1 geometry passes; 2×8 B depth + 2×16 B layers + 2×16 B accumulation (2×64 B fold states for translucency and fresnel) + 20 B per pixel"
    }
    fn exact(&self) -> bool {
        true
    }
    fn axes(&self) -> Vec<Axis> {
        let mut v = vec![MAX_LAYERS, OCCLUSION_STOP];
        v.extend_from_slice(effects::AXES);
        v
    }
    fn validate(&self, point: &Point) -> std::result::Result<(), InvalidPoint> {
        EffectConfig::from_point(point).map(|_| ())
    }
    fn payload(&self, point: &Point) -> Option<&'static str> {
        let e = effect_of(point).ok()?;
        Some(
            if fx(&e) {
                Payload::DEPTH_NORMAL
            } else {
                Payload::RGBA
            }
            .name(),
        )
    }
    fn required_features(&self) -> wgpu::Features {
        wgpu::Features::FLOAT32_BLENDABLE
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        effect_of(point)?;
        for f in [DEPTH_FORMAT, LAYER_FORMAT] {
            if !gpu.renderable(f) {
                return Err(format!("{f:?} is not renderable on this adapter").into());
            }
        }
        // The peel pass writes the depth pair and the front and back layers at once: checked
        // here, before any GPU work, not left to the pipeline's validation error.
        let need: u32 = [DEPTH_FORMAT, LAYER_FORMAT, LAYER_FORMAT]
            .iter()
            .map(|f| f.block_copy_size(None).unwrap_or(16))
            .sum();
        let have = gpu.limits.max_color_attachment_bytes_per_sample;
        if need > have {
            return Err(format!(
                "{need} bytes per sample in colour attachments needed (a depth pair, the front and \
                 back layers in one pass), {} allows {have}",
                gpu.profile.who()
            )
            .into());
        }
        Ok(())
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let max_layers = point.int(&MAX_LAYERS) as u32;
        let occlusion_stop = point.bool(&OCCLUSION_STOP);
        let effect = effect_of(point)?;
        Ok(Box::new(PreparedDual::new(
            gpu,
            scene,
            max_layers.div_ceil(2),
            occlusion_stop,
            &effect,
        )))
    }
}

struct PreparedDual {
    init: wgpu::RenderPipeline,
    peel: wgpu::RenderPipeline,
    composite: wgpu::ComputePipeline,
    combine: wgpu::ComputePipeline,
    /// Per parity q: peel pass i (i % 2 == q) reads depth[1 − q] and writes depth[q].
    peel_bind: [wgpu::BindGroup; 2],
    comp_bind: [wgpu::BindGroup; 2],
    depth: [wgpu::TextureView; 2],
    front: wgpu::TextureView,
    back: wgpu::TextureView,
    front_acc: wgpu::Buffer,
    back_acc: wgpu::Buffer,
    counts: wgpu::Buffer,
    remaining: wgpu::Buffer,
    remaining_read: wgpu::Buffer,
    image: wgpu::Buffer,
    max_peels: u32,
    occlusion_stop: bool,
    alloc: AllocCounter,
}

impl PreparedDual {
    fn new(
        gpu: &Gpu,
        scene: &GpuScene,
        max_peels: u32,
        occlusion_stop: bool,
        effect: &EffectConfig,
    ) -> Self {
        let d = &gpu.device;
        let (w, h) = (scene.width, scene.height);
        let module = shader(gpu, "dual_peel", &format!("{FOLD_WGSL}\n{WGSL}"));
        let fx = fx(effect);
        let mut constants = effect.constants();
        constants.push(("FX", if fx { 1.0 } else { 0.0 }));
        let constants = &constants[..];
        let frag = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let comp = wgpu::ShaderStages::COMPUTE;
        let peel_b = Bindings::seq(gpu, "dual peel", frag, &[B::Camera, B::Texture(FLOAT)]);
        // Composite: the two depth targets, the front and back layers; the accumulations,
        // counts, the remaining-pixels counter and the image.
        let mut kinds = vec![B::Texture(FLOAT); 4];
        kinds.extend([B::Storage; 5]);
        let comp_b = Bindings::seq(gpu, "dual peel composite", comp, &kinds);
        let peel_layout = pipeline_layout(gpu, "dual peel", &[&peel_b.layout]);
        let comp_layout = pipeline_layout(
            gpu,
            "dual peel composite",
            &[&peel_b.layout, &comp_b.layout],
        );
        let max = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Max,
        };
        let layouts: Vec<_> = GpuScene::layouts(Attrs::ALL)
            .into_iter()
            .map(Some)
            .collect();
        let make = |label: &str, fs: &str, targets: &[Option<wgpu::ColorTargetState>]| {
            let raster = Raster {
                module: &module,
                vs: "vs_full",
                buffers: &layouts,
                fs,
                targets,
                constants,
                depth: None,
                samples: 1,
            };
            render_pipeline(gpu, label, &peel_layout, raster)
        };
        let init = make("dual peel init", "fs_init", &[blended(DEPTH_FORMAT, max)]);
        let peel = make(
            "dual peel",
            "fs_peel",
            &[
                blended(DEPTH_FORMAT, max),
                blended(LAYER_FORMAT, max),
                blended(LAYER_FORMAT, max),
            ],
        );
        let composite = compute_pipeline(
            gpu,
            "dual composite",
            &comp_layout,
            &module,
            "composite",
            constants,
            false,
        );
        let combine = compute_pipeline(
            gpu,
            "dual combine",
            &comp_layout,
            &module,
            "combine",
            constants,
            false,
        );

        let mut alloc = AllocCounter::default();
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let depth = [0, 1].map(|i| {
            alloc
                .texture(gpu, &format!("dual depth {i}"), w, h, DEPTH_FORMAT, usage)
                .create_view(&Default::default())
        });
        let front = alloc
            .texture(gpu, "dual front layer", w, h, LAYER_FORMAT, usage)
            .create_view(&Default::default());
        let back = alloc
            .texture(gpu, "dual back layer", w, h, LAYER_FORMAT, usage)
            .create_view(&Default::default());
        let px = scene.pixels() as u64;
        // A premultiplied colour per pixel, or an effects fold state (FX).
        let acc = if fx { FOLD_STATE_BYTES } else { 16 };
        let front_acc = alloc.buffer(gpu, "dual front accum", px * acc, STORAGE_RW);
        let back_acc = alloc.buffer(gpu, "dual back accum", px * acc, STORAGE_RW);
        let counts = alloc.buffer(gpu, "dual counts", px * 4, STORAGE_RW);
        let image = alloc.buffer(gpu, "dual image", px * 16, STORAGE_RW);
        let remaining = alloc.buffer(gpu, "dual remaining", 4, STORAGE_RW);
        let remaining_read = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("dual remaining read"),
            size: 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let peel_bind = [0usize, 1]
            .map(|q| peel_b.group(gpu, &[(&scene.camera).into(), (&depth[1 - q]).into()]));
        let comp_bind = [0usize, 1].map(|q| {
            let res: [Res; 9] = [
                (&depth[1 - q]).into(),
                (&depth[q]).into(),
                (&front).into(),
                (&back).into(),
                (&front_acc).into(),
                (&back_acc).into(),
                (&counts).into(),
                (&remaining).into(),
                (&image).into(),
            ];
            comp_b.group(gpu, &res)
        });
        PreparedDual {
            init,
            peel,
            composite,
            combine,
            peel_bind,
            comp_bind,
            depth,
            front,
            back,
            front_acc,
            back_acc,
            counts,
            remaining,
            remaining_read,
            image,
            max_peels,
            occlusion_stop,
            alloc,
        }
    }

    fn attachment(
        view: &wgpu::TextureView,
        clear: f64,
    ) -> Option<wgpu::RenderPassColorAttachment<'_>> {
        bench_core::gpu::cleared(
            view,
            wgpu::Color {
                r: clear,
                g: clear,
                b: clear,
                a: clear,
            },
        )
    }

    fn compute(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        scene: &GpuScene,
        q: usize,
        combine: bool,
    ) {
        let label = if combine { "combine" } else { "composite" };
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: timer.compute_pass(label),
        });
        pass.set_pipeline(if combine {
            &self.combine
        } else {
            &self.composite
        });
        pass.set_bind_group(0, &self.peel_bind[q], &[]);
        pass.set_bind_group(1, &self.comp_bind[q], &[]);
        pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
    }
}

impl bench_core::timed::Timed for PreparedDual {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.front_acc, 0, None);
        enc.clear_buffer(&self.back_acc, 0, None);
        enc.clear_buffer(&self.counts, 0, None);
        enc.clear_buffer(&self.remaining, 0, None);
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("init"),
                color_attachments: &[Self::attachment(&self.depth[0], -BIG)],
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("init"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.init);
            // Parity 0 reads depth[1]: the init pass writes depth[0] and reads nothing.
            pass.set_bind_group(0, &self.peel_bind[0], &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        let mut stats = FrameStats {
            geometry_passes: 1,
            layers: 0,
        };
        let mut last_q = 0;
        for i in 1..=self.max_peels {
            let q = (i % 2) as usize;
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("peel"),
                    color_attachments: &[
                        Self::attachment(&self.depth[q], -BIG),
                        Self::attachment(&self.front, -BIG),
                        Self::attachment(&self.back, -BIG),
                    ],
                    depth_stencil_attachment: None,
                    timestamp_writes: timer.render_pass("peel"),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.peel);
                pass.set_bind_group(0, &self.peel_bind[q], &[]);
                scene.draw(&mut pass, Attrs::ALL);
            }
            enc.clear_buffer(&self.remaining, 0, None);
            self.compute(&mut enc, timer, scene, q, false);
            stats.geometry_passes += 1;
            stats.layers += 2;
            last_q = q;
            if self.occlusion_stop && i < self.max_peels {
                // Like classic peeling's occlusion query: the CPU reads the count before
                // deciding on another pass.
                enc.copy_buffer_to_buffer(&self.remaining, 0, &self.remaining_read, 0, 4);
                gpu.queue.submit([enc.finish()]);
                let bytes = gpu.map_read(&self.remaining_read)?;
                enc = gpu.device.create_command_encoder(&Default::default());
                if u32::from_le_bytes(bytes[..4].try_into().unwrap()) == 0 {
                    break;
                }
            }
        }
        self.compute(&mut enc, timer, scene, last_q, true);
        gpu.queue.submit([enc.finish()]);
        Ok(stats)
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl Prepared for PreparedDual {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let n = scene.pixels();
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, n)?);
        cap.counts = Some(read_vec::<u32>(gpu, &self.counts, n)?);
        cap.expected = Expected::All;
        let left = read_vec::<u32>(gpu, &self.remaining, 1)?[0] as u64;
        cap.overflow_pixels = Some(left);
        if left > 0 {
            cap.flag.add(Flag::Overflow);
            cap.notes = format!(
                "{left} pixels kept unpeeled middle layers after {} peel passes",
                self.max_peels
            );
        }
        Ok(cap)
    }
}

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::{Bool, Int};

    use super::*;
    use crate::testing::{assert_matches_reference, max_err, params, point, run, scene};
    use mfx_reference::metrics::{image_error, BAD_PIXEL_TOL};
    use scenarios::ParamValue::{Float, Str};
    use scenarios::Params;

    /// Front and back halves composited separately then combined: a few f32 ulps per layer.
    const IMAGE_TOL: f64 = 2e-5;

    #[test]
    fn equals_the_reference_with_half_the_passes() {
        let shells = scene("shells", &[("count", Int(3)), ("segments", Int(12))]);
        let quads = scene("quads", &[("depth_complexity", Int(7))]);
        let grass = scene("grass", &[("blades", Int(200))]);
        let points: Vec<Params> = [true, false]
            .map(|stop| params(&[("max_layers", Int(64)), ("occlusion_stop", Bool(stop))]))
            .into();
        assert_matches_reference(
            &DualPeel,
            &[&shells, &quads, &grass],
            &points,
            (40, 40),
            IMAGE_TOL,
            "front and back halves composited separately in f32",
            |name, cap| assert_eq!(cap.overflow_pixels, Some(0), "{name}: {}", cap.notes),
        );
    }

    #[test]
    fn passes_are_half_the_layers_plus_one_and_too_few_are_reported() {
        let s = scene("quads", &[("depth_complexity", Int(7))]);
        let gpu = crate::testing::gpu();
        let gs = GpuScene::upload(gpu, &s, 32, 32);
        let p = params(&[("max_layers", Int(64))]);
        let m = crate::method::measure(
            gpu,
            &gs,
            &DualPeel,
            &crate::testing::point(&DualPeel, &p),
            &bench_core::measure::TimingPlan::once(),
        )
        .unwrap();
        let n = mfx_reference::rasterize(&s, 32, 32).max_depth_complexity();
        assert_eq!(m.frame.geometry_passes, n.div_ceil(2) + 1, "{n} layers");
        // Four layers' worth of passes on seven layers: the middle is missing, and said so.
        let p = params(&[("max_layers", Int(4)), ("occlusion_stop", Bool(false))]);
        let (cap, _) = run(&DualPeel, &s, 32, 32, &p);
        assert!(cap.overflow_pixels.unwrap() > 0);
        assert_eq!(cap.flag, Flag::Overflow.into());
    }

    /// Effects reading interpolated view depth and normals, as `tests/effects.rs` judges depth
    /// peeling: max abs ≤ 2e-3, RMSE ≤ 2e-4. The GPU interpolates view_z from unsnapped vertex
    /// positions while the reference snaps to 1/256 px, so at sphere silhouettes (view_z moving
    /// ~0.5 per pixel) a fragment's depth differs by up to 0.5/512 ≈ 1e-3, and σ·Δl ≤ 1e-3 for
    /// σ ≤ 1; the f32 folds and the one combining step add ~1e-6.
    const FX_MAX: f64 = 2e-3;
    const FX_RMSE: f64 = 2e-4;

    /// (max abs, RMSE) of dual peeling's effect image against the f64 reference of its effect.
    fn fx_err(s: &scenarios::Scene, p: &Params, w: u32) -> (f64, f64, Capture) {
        let (cap, lists) = run(&DualPeel, s, w, w, p);
        let cfg = EffectConfig::from_point(&point(&DualPeel, p)).unwrap();
        let reference = cfg.reference(s, &lists, cap.expected);
        let e = image_error(&reference, cap.image.as_ref().unwrap(), BAD_PIXEL_TOL);
        assert_eq!(e.non_finite, 0, "{}: NaN/Inf", p.label());
        (e.max_abs, e.rmse, cap)
    }

    #[test]
    fn translucency_and_fresnel_from_both_ends_match_the_f64_reference_48px() {
        // 3 nested shells: 6 layers, 3 peeled from the front and 3 from the back, so every
        // covered pixel's image depends on the combining step; odd max_layers leaves a pass with
        // near == far (the front sweep alone).
        let shells = scene("shells", &[("count", Int(3)), ("segments", Int(16))]);
        let mut cases = Vec::new();
        for effect in ["translucency", "fresnel"] {
            for thickness in ["stable", "naive"] {
                for stop in [true, false] {
                    cases.push(params(&[
                        ("effect", Str(effect.into())),
                        ("sigma", Float(0.8)),
                        ("thickness", Str(thickness.into())),
                        ("max_layers", Int(64)),
                        ("occlusion_stop", Bool(stop)),
                    ]));
                }
            }
        }
        for p in &cases {
            let (m, r, cap) = fx_err(&shells, p, 48);
            assert!(m <= FX_MAX, "{}: max abs {m} > {FX_MAX}", p.label());
            assert!(r <= FX_RMSE, "{}: RMSE {r} > {FX_RMSE}", p.label());
            assert_eq!(cap.overflow_pixels, Some(0), "{}", cap.notes);
        }
    }

    #[test]
    fn the_two_sweeps_are_both_used_and_fresnel_differs_from_translucency() {
        // Guards against a combine that drops one end: the front sweep alone (max_layers 2:
        // one pass, the nearest and farthest layer) is far from the reference on 6 layers,
        // and flagged; Fresnel's product is not the plain transmittance.
        let shells = scene("shells", &[("count", Int(3)), ("segments", Int(16))]);
        let p = |e: &str, layers: i64| {
            params(&[
                ("effect", Str(e.into())),
                ("sigma", Float(0.8)),
                ("max_layers", Int(layers)),
                ("occlusion_stop", Bool(false)),
            ])
        };
        let (m, _, cap) = fx_err(&shells, &p("translucency", 2), 32);
        assert!(cap.overflow_pixels.unwrap() > 0);
        assert!(m > 0.05, "2 of 6 layers: max abs {m}");
        let (a, _) = run(&DualPeel, &shells, 32, 32, &p("translucency", 64));
        let (b, _) = run(&DualPeel, &shells, 32, 32, &p("fresnel", 64));
        assert_ne!(a.image, b.image);
        assert_eq!(
            DualPeel.payload(&point(&DualPeel, &p("fresnel", 64))),
            Some("depth_normal")
        );
    }

    #[test]
    fn csg_and_dof_are_skipped_with_the_reason_transparency_unchanged() {
        let gpu = crate::testing::gpu();
        for e in ["csg_and", "dof"] {
            let why = DualPeel
                .supports(
                    gpu,
                    &point(&DualPeel, &params(&[("effect", Str(e.into()))])),
                )
                .unwrap_err();
            assert!(why.contains(e), "{why}");
        }
        let quads = scene("quads", &[("depth_complexity", Int(7))]);
        let p = params(&[
            ("effect", Str("transparency".into())),
            ("max_layers", Int(64)),
        ]);
        let (cap, lists) = run(&DualPeel, &quads, 32, 32, &p);
        let (e, at) = max_err(&cap, &lists);
        assert!(e <= IMAGE_TOL, "error {e} at pixel {at}");
    }
}
