//! Weighted blended OIT (McGuire & Bavoil 2013): one geometry pass into an RGBA16F weighted sum
//! (additive blending) and an R16F revealage (multiplicative blending), then a compute resolve.
//! Approximate (`exact() = false`): its error vs the reference is what the rows report. It walks
//! no fragment list, so the effects fold does not apply (transparency only).
//!
//! Antialiasing (`aa`): with MSAA both targets are multisampled and blended per sample
//! (`aa_capture = coverage`: shaded once per pixel, the hardware writes the covered samples;
//! `sample`: shaded per sample), and the resolve composites each sample and averages: 8 + 2 B
//! per sample. `ssaa2x2` renders at twice the width and height and box-filters.

use crate::aa::{self, AaConfig, AaMode, AaSupport};
use bench_core::axes::{Axis, Point};
use bench_core::gpu_util::{
    compute_pipeline, per_sample_source, pixel_pass, read_vec, shader, shader_source, COMMON_WGSL,
    STORAGE_RW,
};

use super::{Capture, Expected, FrameStats, Method, Prepared};
use bench_core::bind::{pipeline_layout, render_pipeline, Bindings, Kind as B, Raster, FLOAT};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::timing::GpuTimer;
use bench_core::Result;

const WGSL: &str = include_str!("wboit.wgsl");
const ACCUM: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const REVEAL: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

pub struct Wboit;

const AA_SUPPORT: AaSupport = AaSupport {
    sample: true,
    coverage: true,
    ssaa: true,
    why: "",
};

impl Method for Wboit {
    fn name(&self) -> &'static str {
        "wboit"
    }
    fn describe(&self) -> &'static str {
        "McGuire & Bavoil 2013: weighted blended OIT, approximate; 1 geometry pass + resolve; 8 B RGBA16F + 2 B R16F + 16 B result per pixel"
    }
    fn exact(&self) -> bool {
        false
    }
    fn axes(&self) -> Vec<Axis> {
        vec![aa::AA, aa::AA_CAPTURE]
    }
    fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        for f in [ACCUM, REVEAL] {
            if !gpu.renderable(f) {
                return Err(format!("{f:?} is not renderable on this adapter").into());
            }
        }
        let cfg = AaConfig::from_point(point);
        AA_SUPPORT.check(self.name(), cfg)?;
        aa::check_adapter(gpu, cfg, &[ACCUM, REVEAL])
    }
    fn prepare(&self, gpu: &Gpu, scene: &GpuScene, point: &Point) -> Result<Box<dyn Prepared>> {
        let cfg = AaConfig::from_point(point);
        if cfg.mode == AaMode::Ssaa2x2 {
            return super::shared::ssaa::prepare(gpu, scene, |big| {
                Ok(Box::new(PreparedWboit::new(gpu, big, AaConfig::NONE)))
            });
        }
        Ok(Box::new(PreparedWboit::new(gpu, scene, cfg)))
    }
}

struct PreparedWboit {
    accum_pass: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
    cam_bind: wgpu::BindGroup,
    res_bind: wgpu::BindGroup,
    accum: wgpu::TextureView,
    reveal: wgpu::TextureView,
    image: wgpu::Buffer,
    aa: AaConfig,
    sample_positions: Option<String>,
    alloc: AllocCounter,
}

impl PreparedWboit {
    fn new(gpu: &Gpu, scene: &GpuScene, aa: AaConfig) -> Self {
        let samples = aa.msaa();
        let module = if samples > 1 && aa.capture == aa::AaCapture::Sample {
            let src = per_sample_source(&format!("{COMMON_WGSL}\n{WGSL}"));
            shader_source(gpu, "wboit (per sample)", src)
        } else {
            shader(gpu, "wboit", WGSL)
        };
        let ms = samples > 1;
        let comp = wgpu::ShaderStages::COMPUTE;
        let cam = Bindings::seq(gpu, "wboit camera", comp, &[B::Camera]);
        // The resolve reads the accumulation and revealage targets (bindings 4, 5 when
        // multisampled) and writes the image.
        let (a, r, tex) = if ms {
            (4, 5, B::TextureMs(FLOAT))
        } else {
            (1, 2, B::Texture(FLOAT))
        };
        let rows = [(0, B::Camera), (a, tex), (r, tex), (3, B::Storage)];
        let res = Bindings::new(gpu, "wboit resolve", comp, &rows);
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        // dst · (1 − src): the revealage product.
        let mul = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::OneMinusSrc,
            operation: wgpu::BlendOperation::Add,
        };
        let targets = [
            Some(wgpu::ColorTargetState {
                format: ACCUM,
                blend: Some(wgpu::BlendState {
                    color: add,
                    alpha: add,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            }),
            Some(wgpu::ColorTargetState {
                format: REVEAL,
                blend: Some(wgpu::BlendState {
                    color: mul,
                    alpha: mul,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            }),
        ];
        let layouts: Vec<_> = GpuScene::layouts(Attrs::ALL)
            .into_iter()
            .map(Some)
            .collect();
        let raster = Raster {
            module: &module,
            vs: "vs_full",
            buffers: &layouts,
            fs: "fs_accum",
            targets: &targets,
            constants: &[],
            depth: None,
            samples,
        };
        let accum_layout = pipeline_layout(gpu, "wboit", &[&cam.layout]);
        let accum_pass = render_pipeline(gpu, "wboit accumulate", &accum_layout, raster);
        let resolve = compute_pipeline(
            gpu,
            "wboit resolve",
            &pipeline_layout(gpu, "wboit", &[&res.layout]),
            &module,
            if ms { "resolve_ms" } else { "resolve" },
            &[],
            false,
        );
        let mut alloc = AllocCounter::default();
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let (w, h) = (scene.width, scene.height);
        let accum = alloc
            .texture_ms(gpu, "wboit accum", w, h, ACCUM, usage, samples)
            .create_view(&Default::default());
        let reveal = alloc
            .texture_ms(gpu, "wboit revealage", w, h, REVEAL, usage, samples)
            .create_view(&Default::default());
        let image = alloc.buffer(gpu, "wboit image", scene.pixels() as u64 * 16, STORAGE_RW);
        let cam_bind = cam.group(gpu, &[(&scene.camera).into()]);
        let res_bind = res.group(
            gpu,
            &[
                (&scene.camera).into(),
                (&accum).into(),
                (&reveal).into(),
                (&image).into(),
            ],
        );
        PreparedWboit {
            accum_pass,
            resolve,
            cam_bind,
            res_bind,
            accum,
            reveal,
            image,
            aa,
            sample_positions: ms.then(|| aa::sample_positions(gpu, samples)),
            alloc,
        }
    }
}

impl bench_core::timed::Timed for PreparedWboit {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let att = |view, clear: f64| {
                bench_core::gpu::cleared(
                    view,
                    wgpu::Color {
                        r: clear,
                        g: clear,
                        b: clear,
                        a: clear,
                    },
                )
            };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("accumulate"),
                color_attachments: &[att(&self.accum, 0.0), att(&self.reveal, 1.0)],
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("accumulate"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.accum_pass);
            pass.set_bind_group(0, &self.cam_bind, &[]);
            scene.draw(&mut pass, Attrs::ALL);
        }
        pixel_pass(
            &mut enc,
            timer,
            "resolve",
            &self.resolve,
            &self.res_bind,
            scene,
        );
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

impl Prepared for PreparedWboit {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.image, scene.pixels())?);
        cap.expected = Expected::All;
        cap.notes = "approximate: weighted average colour (RGBA16F), revealage R16F".into();
        // No `aa_capture`: WBOIT's own definition is WBOIT, not an exact per-sample composite.
        cap.aa = self.aa.capture_mode();
        cap.sample_positions = self.sample_positions.clone();
        Ok(cap)
    }

    fn image_buffer(&self) -> Option<&wgpu::Buffer> {
        Some(&self.image)
    }
}

/// The f16 bound of the tests below, for the AA tests.
#[cfg(test)]
fn tests_bound(layers: u32) -> f64 {
    (2 * layers + 2) as f64 * 2f64.powi(-11)
}

#[cfg(test)]
mod tests {
    use scenarios::ParamValue::Int;

    use super::*;
    use crate::testing::{max_err, run, scene};

    /// f16 has an 11-bit significand: each stored sum or product is within 2^-11 relative, so a
    /// pixel of n layers (n rounded additions in each channel of the sum, n rounded products in
    /// the revealage, one division) stays within (2n + 2)·2^-11 of the exact value (≤ 1).
    fn f16_bound(layers: u32) -> f64 {
        (2 * layers + 2) as f64 * 2f64.powi(-11)
    }

    #[test]
    fn exact_up_to_f16_rounding_on_one_layer() {
        let s = scene("quads", &[("depth_complexity", Int(1))]);
        let (cap, lists) = run(&Wboit, &s, 32, 32, &Default::default());
        assert_eq!(lists.max_depth_complexity(), 1);
        let (e, at) = max_err(&cap, &lists);
        assert!(e <= f16_bound(1), "error {e} at pixel {at}");
    }

    #[test]
    fn exact_up_to_f16_rounding_when_every_layer_has_one_colour() {
        // WBOIT's weighted average of one colour is that colour, and its revealage is the exact
        // transmittance: the only error is rounding.
        let mut s = scene("quads", &[("depth_complexity", Int(6))]);
        for c in s.mesh.colors.iter_mut() {
            *c = [0.8, 0.3, 0.1, 0.4];
        }
        let (cap, lists) = run(&Wboit, &s, 32, 32, &Default::default());
        let n = lists.max_depth_complexity();
        assert!(n >= 4, "the scene has several layers ({n})");
        let (e, at) = max_err(&cap, &lists);
        assert!(
            e <= f16_bound(n),
            "error {e} at pixel {at} (bound {})",
            f16_bound(n)
        );
        // And with distinct colours it is approximate: the error is reported, not hidden.
        let s = scene("quads", &[("depth_complexity", Int(6))]);
        let (cap, lists) = run(&Wboit, &s, 32, 32, &Default::default());
        let (e, _) = max_err(&cap, &lists);
        assert!(
            e > f16_bound(n),
            "distinct colours give a real approximation error ({e})"
        );
    }
}

#[cfg(test)]
mod aa_tests {
    use scenarios::ParamValue::{Int, Str};

    use super::*;
    use crate::testing::{gpu, max_err_vs, params, point, run_truth, scene};

    /// Every `aa` × `aa_capture` this adapter runs, and the reasons of those it skips.
    fn modes(s: &scenarios::Scene, bound: f64) -> Vec<String> {
        let mut ran = Vec::new();
        for mode in AaMode::NAMES {
            for capture in ["sample", "coverage"] {
                let p = params(&[
                    ("aa", Str(mode.to_string())),
                    ("aa_capture", Str(capture.into())),
                ]);
                if let Err(why) = Wboit.supports(gpu(), &point(&Wboit, &p)) {
                    assert!(why.contains("multisampled"), "{mode}/{capture}: {why}");
                    continue;
                }
                let (cap, truth) = run_truth(&Wboit, s, 32, 32, &p);
                let (e, at) = max_err_vs(&cap, &truth);
                assert!(
                    e <= bound,
                    "{} aa={mode} {capture}: error {e} at pixel {at} (bound {bound})",
                    s.label()
                );
                ran.push(format!("{mode}/{capture}"));
            }
        }
        ran
    }

    #[test]
    fn one_colour_layers_match_the_multisampled_truth_up_to_f16_in_every_aa_mode() {
        // Per sample WBOIT is exact for one layer or one colour (see the tests above); its
        // resolve averages per-sample composites exactly as the truth averages samples, so each
        // mode is within the same f16 bound, now also at the antialiased edges.
        let one = scene("quads", &[("depth_complexity", Int(1))]);
        let ran = modes(&one, super::tests_bound(1));
        assert!(ran.contains(&"msaa4/sample".to_string()), "{ran:?}");
        assert!(ran.contains(&"msaa4/coverage".to_string()), "{ran:?}");
        assert!(ran.contains(&"ssaa2x2/sample".to_string()), "{ran:?}");
        let mut s = scene("quads", &[("depth_complexity", Int(6))]);
        for c in s.mesh.colors.iter_mut() {
            *c = [0.8, 0.3, 0.1, 0.4];
        }
        modes(&s, super::tests_bound(6));
        // The edges are really antialiased: the truth has fractional alpha where one sample
        // does not.
        let p = params(&[("aa", Str("msaa4".into()))]);
        let (cap, truth) = run_truth(&Wboit, &one, 32, 32, &p);
        assert_eq!(cap.aa, Some(AaMode::Msaa(4)));
        assert_eq!(cap.sample_positions.as_deref(), Some("standard"));
        assert!(truth.iter().any(|t| t[3] > 0.05 && t[3] < 0.3));
    }
}
