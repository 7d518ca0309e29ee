//! Antialiasing: the `aa` and `aa_capture` axes every AA-capable method declares, the
//! multisampled ground truth its rows are judged against ([`truth`], [`ground_truth`]), and the
//! per-adapter probe that checks the GPU samples where the reference does ([`sample_positions`]).
//!
//! The truth is the mean over a pixel's samples of each sample's exact composite (or effect),
//! at Vulkan's standard sample locations (`reference::multisample`); `ssaa2x2` is the exact
//! reference at twice the width and height, 2×2 box-filtered. `aa = none` is the single-sample
//! path, unchanged.
//!
//! wgpu does not report sample locations, so a probe render (16×2 pixels, one thin rectangle
//! per pixel whose edge cuts it at a known 1/32 offset) reads back each sample's coverage and
//! compares it with what the reference decides at the standard positions; where they differ the
//! measured positions (to 1/16 px) are reported. It runs once per adapter and sample count.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex, OnceLock};

use scenarios::Scene;

use crate::effects::EffectConfig;
use crate::method::{Capture, Expected};
use bench_core::axes::{Axis, Point};
use bench_core::gpu::Gpu;
use bench_core::record::cols;
use mfx_reference::multisample::{
    box_filter_2x2, coverage_lists, sample_list, sample_list_centre_attributes, standard_positions,
};
use mfx_reference::raster::{covers, top_left_edges};
use mfx_reference::{rasterize, FragmentLists};

pub use mfx_reference::multisample::AaCapture;
pub use mfx_reference::AaMode;

pub const AA: Axis = Axis::choice(
    cols::AA,
    "antialiasing: none | msaa2 | msaa4 | msaa8 (standard sample positions) | ssaa2x2 (2× width and height, box-filtered); each method supports some, the rest are skipped",
    "none",
    AaMode::NAMES,
);
pub const AA_CAPTURE: Axis = Axis::choice(
    cols::AA_CAPTURE,
    "MSAA capture: sample (sample shading, one fragment per covered sample) | coverage (one fragment per pixel with its coverage mask, resolved per sample)",
    "sample",
    &["sample", "coverage"],
)
.only_when(&AA, &["msaa2", "msaa4", "msaa8"]);

/// A point's antialiasing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AaConfig {
    pub mode: AaMode,
    pub capture: AaCapture,
}

impl AaConfig {
    pub const NONE: AaConfig = AaConfig {
        mode: AaMode::None,
        capture: AaCapture::Sample,
    };

    /// Reads `aa` and `aa_capture` (both declared by the method).
    pub fn from_point(point: &Point) -> AaConfig {
        let mode = AaMode::parse(&point.choice(&AA)).expect("checked against AaMode::NAMES");
        let capture = match point.choice(&AA_CAPTURE).as_str() {
            "coverage" => AaCapture::Coverage,
            _ => AaCapture::Sample,
        };
        AaConfig { mode, capture }
    }

    /// MSAA render-target samples (1 unless MSAA).
    pub fn msaa(&self) -> u32 {
        self.mode.msaa_samples()
    }

    /// The mode a capture reports: `None` for `aa = none` (the single-sample judge).
    pub fn capture_mode(&self) -> Option<AaMode> {
        (self.mode != AaMode::None).then_some(self.mode)
    }
}

/// What a method can do with each mode: checked in its `supports` (the rest are skipped).
#[derive(Clone, Copy, Debug)]
pub struct AaSupport {
    /// MSAA with `aa_capture = sample`.
    pub sample: bool,
    /// MSAA with `aa_capture = coverage`.
    pub coverage: bool,
    /// `ssaa2x2`.
    pub ssaa: bool,
    /// Why a missing variant is missing (one line, in the skip reason).
    pub why: &'static str,
}

impl AaSupport {
    /// `Err(reason)` when `method` cannot run `cfg` at all (any adapter).
    pub fn check(&self, method: &str, cfg: AaConfig) -> Result<(), Unsupported> {
        let ok = match (cfg.mode, cfg.capture) {
            (AaMode::None, _) => true,
            (AaMode::Ssaa2x2, _) => self.ssaa,
            (AaMode::Msaa(_), AaCapture::Sample) => self.sample,
            (AaMode::Msaa(_), AaCapture::Coverage) => self.coverage,
        };
        if ok {
            return Ok(());
        }
        let what = match cfg.mode {
            AaMode::Msaa(_) => format!(
                "aa = {} with aa_capture = {}",
                cfg.mode.name(),
                cfg.capture.name()
            ),
            m => format!("aa = {}", m.name()),
        };
        Err(format!("{method} does not support {what}: {}", self.why).into())
    }
}

pub use bench_core::gpu_util::check_msaa_format;
use bench_core::Unsupported;

/// Whether fragment shaders may run per sample (`@builtin(sample_index)`).
pub fn check_sample_shading(gpu: &Gpu) -> Result<(), Unsupported> {
    if gpu
        .downlevel
        .flags
        .contains(wgpu::DownlevelFlags::MULTISAMPLED_SHADING)
    {
        Ok(())
    } else {
        Err("the adapter cannot shade per sample (no MULTISAMPLED_SHADING)".into())
    }
}

/// The adapter checks of `cfg`: every MSAA target format at its sample count, and sample
/// shading for `aa_capture = sample`.
pub fn check_adapter(
    gpu: &Gpu,
    cfg: AaConfig,
    formats: &[wgpu::TextureFormat],
) -> Result<(), Unsupported> {
    let s = cfg.msaa();
    if s > 1 {
        for &f in formats {
            check_msaa_format(gpu, f, s)?;
        }
        if cfg.capture == AaCapture::Sample {
            check_sample_shading(gpu)?;
        }
    }
    Ok(())
}

/// The multisampled ground truth of one scene, resolution, mode and effect.
#[derive(Clone, Debug)]
pub struct Truth {
    /// The effect's image(s), each pixel the mean of its samples (the `image_count` images one
    /// after another, as in `Capture.image`).
    pub image: Vec<[f64; 4]>,
    /// Most fragments at any one sample of each pixel (a per-sample capacity overflows where
    /// this exceeds it).
    pub depth_complexity: Vec<u32>,
    /// Fragments summed over every sample (what a per-sample capture stores).
    pub sample_fragments: u64,
}

/// The exact multisampled truth: for MSAA the mean over the standard sample positions of the
/// effect on each sample's lists (depth and attributes at the sample), for `ssaa2x2` the
/// reference at (2w)×(2h) box-filtered, for `none` the single-sample reference. `expected`
/// truncates each sample's list (k nearest) as it does a pixel's.
pub fn truth(
    scene: &Scene,
    width: u32,
    height: u32,
    mode: AaMode,
    effect: &EffectConfig,
    expected: Expected,
) -> Truth {
    let n = (width * height) as usize;
    match mode {
        AaMode::None => {
            let lists = rasterize(scene, width, height);
            Truth {
                image: effect.reference(scene, &lists, expected),
                depth_complexity: lists.depth_complexity(),
                sample_fragments: lists.total_fragments(),
            }
        }
        AaMode::Msaa(s) => {
            let positions = standard_positions(s);
            let mut image: Vec<[f64; 4]> = Vec::new();
            let mut dc = vec![0u32; n];
            let mut total = 0;
            // One sample's lists at a time: memory stays that of the single-sample reference.
            for &pos in positions {
                let lists = sample_list(scene, width, height, pos);
                let img = effect.reference(scene, &lists, expected);
                if image.is_empty() {
                    image = vec![[0.0; 4]; img.len()];
                }
                for (o, x) in image.iter_mut().zip(&img) {
                    for c in 0..4 {
                        o[c] += x[c];
                    }
                }
                for (d, l) in dc.iter_mut().zip(lists.depth_complexity()) {
                    *d = (*d).max(l);
                }
                total += lists.total_fragments();
            }
            for o in &mut image {
                for c in o.iter_mut() {
                    *c /= positions.len() as f64;
                }
            }
            Truth {
                image,
                depth_complexity: dc,
                sample_fragments: total,
            }
        }
        AaMode::Ssaa2x2 => {
            let lists = rasterize(scene, 2 * width, 2 * height);
            let big = effect.reference(scene, &lists, expected);
            let bdc = lists.depth_complexity();
            let dc = (0..n)
                .map(|p| {
                    let (x, y) = ((p % width as usize) * 2, (p / width as usize) * 2);
                    let w2 = 2 * width as usize;
                    [0, 1, w2, w2 + 1]
                        .iter()
                        .map(|&o| bdc[y * w2 + x + o])
                        .max()
                        .unwrap_or(0)
                })
                .collect();
            Truth {
                image: box_filter_2x2(&big, width, height),
                depth_complexity: dc,
                sample_fragments: lists.total_fragments(),
            }
        }
    }
}

/// A coverage-mask capture's own definition: per sample, the effect over the fragments whose
/// mask covers it, with depth order and attributes of the pixel centre; the mean over samples.
/// Equal to [`truth`] where order and colour do not change within a pixel; judged into the
/// `*_vs_k` columns through `Capture.definition`.
pub fn coverage_definition(
    scene: &Scene,
    width: u32,
    height: u32,
    samples: u32,
    effect: &EffectConfig,
    expected: Expected,
) -> Vec<[f64; 4]> {
    let cl = coverage_lists(scene, width, height, samples);
    let per: Vec<Vec<[f64; 4]>> = (0..samples)
        .map(|s| effect.reference(scene, &cl.sample(s), expected))
        .collect();
    mfx_reference::multisample::resolve(&per)
}

/// A per-sample capture's own definition when its inputs are interpolated at the pixel centre
/// (lavapipe): per sample, coverage, depth and order there, attributes at the centre; the mean
/// over samples. Equal to [`truth`] for attributes constant over each triangle (every colour of
/// the generators), different for view depth and normals.
pub fn sample_definition(
    scene: &Scene,
    width: u32,
    height: u32,
    samples: u32,
    effect: &EffectConfig,
    expected: Expected,
) -> Vec<[f64; 4]> {
    let per: Vec<Vec<[f64; 4]>> = standard_positions(samples)
        .iter()
        .map(|&pos| {
            let lists = sample_list_centre_attributes(scene, width, height, pos);
            effect.reference(scene, &lists, expected)
        })
        .collect();
    mfx_reference::multisample::resolve(&per)
}

/// The image an MSAA capture's own rule gives (the `*_vs_k` columns; the judge has the scene,
/// `Prepared::judge` does not): coverage masks → [`coverage_definition`], per sample →
/// [`sample_definition`], each over the capture's `expected` set per sample; `None` for other
/// captures.
pub fn definition(
    cap: &Capture,
    scene: &Scene,
    width: u32,
    height: u32,
    effect: &EffectConfig,
) -> Option<Vec<[f64; 4]>> {
    let Some(AaMode::Msaa(s)) = cap.aa else {
        return None;
    };
    Some(match cap.aa_capture? {
        AaCapture::Coverage => coverage_definition(scene, width, height, s, effect, cap.expected),
        AaCapture::Sample => sample_definition(scene, width, height, s, effect, cap.expected),
    })
}

/// [`definition`], kept for the last few (scene, size, capture rule, effect, expected set).
fn definition_cached(
    cap: &Capture,
    scene: &Scene,
    width: u32,
    height: u32,
    effect: &EffectConfig,
) -> Option<Arc<Vec<[f64; 4]>>> {
    type Key = (u64, u32, u32, String, String, String);
    static CACHE: Memo<Key, Vec<[f64; 4]>> = OnceLock::new();
    let (Some(AaMode::Msaa(_)), Some(_)) = (cap.aa, cap.aa_capture) else {
        return None;
    };
    let key: Key = (
        scene_key(scene),
        width,
        height,
        format!("{:?}{:?}", cap.aa, cap.aa_capture),
        format!("{effect:?}"),
        format!("{:?}", cap.expected),
    );
    remembered(&CACHE, key, || {
        definition(cap, scene, width, height, effect)
    })
}

/// A content hash of what the truth depends on (the label alone is not enough: tests edit
/// meshes in place).
fn scene_key(scene: &Scene) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    scene.label().hash(&mut h);
    let m = &scene.mesh;
    bytemuck::cast_slice::<_, u8>(&m.positions).hash(&mut h);
    bytemuck::cast_slice::<_, u8>(&m.colors).hash(&mut h);
    bytemuck::cast_slice::<_, u8>(&m.normals).hash(&mut h);
    m.object_ids.hash(&mut h);
    m.indices.hash(&mut h);
    format!("{:?}", scene.camera).hash(&mut h);
    h.finish()
}

/// [`truth`], remembered for the last few (scene, resolution, mode, effect, expected): every AA
/// row of a group is judged against the same few truths.
pub fn truth_cached(
    scene: &Scene,
    width: u32,
    height: u32,
    mode: AaMode,
    effect: &EffectConfig,
    expected: Expected,
) -> Arc<Truth> {
    type Key = (u64, u32, u32, AaMode, String, String);
    static CACHE: Memo<Key, Truth> = OnceLock::new();
    let key: Key = (
        scene_key(scene),
        width,
        height,
        mode,
        format!("{effect:?}"),
        format!("{expected:?}"),
    );
    remembered(&CACHE, key, || {
        Some(truth(scene, width, height, mode, effect, expected))
    })
    .expect("a truth is always made")
}

/// A few recent (key, value) pairs, shared by the judge's threads.
type Memo<K, V> = OnceLock<Mutex<Vec<(K, Arc<V>)>>>;

/// The value of `key` in `cache` (the last six kept), else what `make` makes, remembered when it
/// makes one.
fn remembered<K: PartialEq, V>(
    cache: &Memo<K, V>,
    key: K,
    make: impl FnOnce() -> Option<V>,
) -> Option<Arc<V>> {
    const KEEP: usize = 6;
    let cache = cache.get_or_init(Default::default);
    if let Some((_, v)) = cache.lock().unwrap().iter().find(|(k, _)| *k == key) {
        return Some(v.clone());
    }
    let v = Arc::new(make()?);
    let mut c = cache.lock().unwrap();
    c.push((key, v.clone()));
    if c.len() > KEEP {
        c.remove(0);
    }
    Some(v)
}

/// The ground truth `cap` is judged against (the judge's rule: the effect over every
/// fragment): the single-sample reference over `lists` when the capture is not antialiased
/// (exactly what it was before AA existed), else the multisampled [`truth`] of its mode.
pub fn ground_truth(
    cap: &Capture,
    scene: &Scene,
    lists: &FragmentLists,
    effect: &EffectConfig,
) -> Vec<[f64; 4]> {
    match antialiased(cap) {
        None => effect.reference(scene, lists, Expected::All),
        Some(mode) => truth_cached(
            scene,
            lists.width,
            lists.height,
            mode,
            effect,
            Expected::All,
        )
        .image
        .clone(),
    }
}

/// The capture's AA mode, `None` for a single-sample one.
pub fn antialiased(cap: &Capture) -> Option<AaMode> {
    cap.aa.filter(|m| *m != AaMode::None)
}

/// Everything the judge needs for an antialiased capture, in one call (`None` for a
/// single-sample capture: the judge's own path, unchanged).
#[derive(Clone, Debug)]
pub struct AaReference {
    pub mode: AaMode,
    /// The ground truth (every fragment, multisampled): `rmse`, `flip_*`, `matches_truth`.
    pub truth: Vec<[f64; 4]>,
    /// The capture's own definition for the `*_vs_k` columns: its k nearest per sample, or its
    /// per-sample / coverage-mask rule ([`definition`]); `None` when that is the truth.
    pub own: Option<Vec<[f64; 4]>>,
    /// Most fragments at one sample of each pixel (a FirstK(k) capture overflows where > k);
    /// replaces `lists.depth_complexity()` for the overflow rate.
    pub depth_complexity: Vec<u32>,
}

/// [`AaReference`] of `cap` (`lists`: the single-sample reference, for its size).
pub fn reference_for(
    cap: &Capture,
    scene: &Scene,
    lists: &FragmentLists,
    effect: &EffectConfig,
) -> Option<AaReference> {
    let mode = antialiased(cap)?;
    let (w, h) = (lists.width, lists.height);
    let all = truth_cached(scene, w, h, mode, effect, Expected::All);
    // The capture's own definition where it brings one; else its rule's image, computed once
    // per scene, view and rule (the judge asks for it, and a path of views asks twice per view:
    // at 1024² a multisampled rule costs about a second).
    let own = match &cap.definition {
        Some(d) => Some(d.clone()),
        None => match definition_cached(cap, scene, w, h, effect) {
            Some(d) => Some(d.to_vec()),
            None => match cap.expected {
                Expected::FirstK(_) => Some(
                    truth_cached(scene, w, h, mode, effect, cap.expected)
                        .image
                        .clone(),
                ),
                Expected::All => None,
            },
        },
    };
    Some(AaReference {
        mode,
        truth: all.image.clone(),
        own,
        depth_complexity: all.depth_complexity.clone(),
    })
}

// ---- the sample-position probe ----

const PROBE_W: u32 = 16;
const PROBE_H: u32 = 2;

const PROBE_WGSL: &str = r#"
@vertex
fn vs(@location(0) p: vec2<f32>) -> @builtin(position) vec4<f32> {
    // Pixel coordinates (y down) of a 16×2 target to NDC; exact in f32 for these dyadic values.
    return vec4<f32>(p.x / 8.0 - 1.0, 1.0 - p.y, 0.0, 1.0);
}
@fragment
fn fs() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0);
}
@group(0) @binding(0) var ms: texture_multisampled_2d<f32>;
@group(0) @binding(1) var<storage, read_write> masks: array<u32>;
@compute @workgroup_size(16, 2)
fn read(@builtin(local_invocation_id) id: vec3<u32>) {
    var m = 0u;
    for (var s = 0u; s < textureNumSamples(ms); s = s + 1u) {
        if textureLoad(ms, vec2<i32>(id.xy), i32(s)).r > 0.5 {
            m = m | (1u << s);
        }
    }
    masks[id.y * 16u + id.x] = m;
}
"#;

/// The probe's rectangles (pixel coordinates, y down): in row 0, pixel i holds x ∈ [i, i + t_i],
/// in row 1, pixel j holds y ∈ [1, 1 + t_j], t = (2i + 1)/32: a sample at offset o is covered
/// in pixel i of row 0 iff o.x < t_i, so the number of uncovered pixels is o.x in sixteenths.
fn probe_rects() -> Vec<[(f64, f64); 2]> {
    let t = |i: u32| (2 * i + 1) as f64 / 32.0;
    let mut r = Vec::new();
    for i in 0..PROBE_W {
        let x = i as f64;
        r.push([(x, 0.0), (x + t(i), 1.0)]);
        r.push([(x, 1.0), (x + 1.0, 1.0 + t(i))]);
    }
    r
}

fn rect_triangles(r: [(f64, f64); 2]) -> [[(f64, f64); 3]; 2] {
    let [(x0, y0), (x1, y1)] = r;
    // Positively wound in y-down screen space (the reference's convention).
    [
        [(x0, y0), (x1, y0), (x1, y1)],
        [(x0, y0), (x1, y1), (x0, y1)],
    ]
}

/// Per-pixel masks the reference gives the probe at `positions` (16×2 pixels, row-major).
fn probe_expected(positions: &[(f64, f64)]) -> Vec<u32> {
    let tris: Vec<[(f64, f64); 3]> = probe_rects().into_iter().flat_map(rect_triangles).collect();
    let mut out = vec![0u32; (PROBE_W * PROBE_H) as usize];
    for y in 0..PROBE_H {
        for x in 0..PROBE_W {
            let mut m = 0;
            for (s, &(ox, oy)) in positions.iter().enumerate() {
                let c = (x as f64 + ox, y as f64 + oy);
                if tris.iter().any(|&t| covers(t, top_left_edges(t), c)) {
                    m |= 1 << s;
                }
            }
            out[(y * PROBE_W + x) as usize] = m;
        }
    }
    out
}

/// Sample positions (to 1/16 px) that the probe's per-pixel masks imply.
fn probe_positions(masks: &[u32], samples: u32) -> Vec<(f64, f64)> {
    (0..samples)
        .map(|s| {
            let uncovered = |row: u32| {
                (0..PROBE_W)
                    .filter(|&i| masks[(row * PROBE_W + i) as usize] & (1 << s) == 0)
                    .count() as f64
                    / 16.0
            };
            (uncovered(0), uncovered(1))
        })
        .collect()
}

/// The probe's verdict from the masks read back (pure: tested without a GPU).
pub fn probe_verdict(masks: &[u32], samples: u32) -> String {
    let standard = standard_positions(samples);
    if masks == probe_expected(standard).as_slice() {
        return "standard".into();
    }
    let got = probe_positions(masks, samples);
    let consistent = probe_expected(&got) == masks;
    let list = got
        .iter()
        .map(|(x, y)| format!("({x:.4},{y:.4})"))
        .collect::<Vec<_>>()
        .join(" ");
    if consistent {
        format!("differs: {list}")
    } else {
        format!("differs: ≈{list} (not on the 1/16 grid)")
    }
}

/// Why the sample positions were not probed (`sample_positions = unverified: <why>`).
#[derive(Debug, thiserror::Error)]
enum ProbeError {
    #[error(transparent)]
    Unsupported(#[from] bench_core::Unsupported),
    #[error("probe render failed: {0}")]
    Render(wgpu::Error),
    #[error("probe read-back failed: {0}")]
    ReadBack(bench_core::CoreError),
}

fn run_probe(gpu: &Gpu, samples: u32) -> Result<Vec<u32>, ProbeError> {
    let format = wgpu::TextureFormat::Rgba8Unorm;
    check_msaa_format(gpu, format, samples)?;
    let d = &gpu.device;
    let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("sample-position probe"),
        source: wgpu::ShaderSource::Wgsl(PROBE_WGSL.into()),
    });
    let verts: Vec<[f32; 2]> = probe_rects()
        .into_iter()
        .flat_map(rect_triangles)
        .flatten()
        .map(|(x, y)| [x as f32, y as f32])
        .collect();
    let vbuf = wgpu::util::DeviceExt::create_buffer_init(
        d,
        &wgpu::util::BufferInitDescriptor {
            label: Some("probe vertices"),
            contents: bytemuck::cast_slice(&verts),
            usage: wgpu::BufferUsages::VERTEX,
        },
    );
    let tex = gpu.create_texture(&wgpu::TextureDescriptor {
        label: Some("probe target"),
        size: wgpu::Extent3d {
            width: PROBE_W,
            height: PROBE_H,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let view = tex.create_view(&Default::default());
    let masks = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe masks"),
        size: (PROBE_W * PROBE_H * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let raster = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("probe raster"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 8,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x2],
            })],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState {
            count: samples,
            mask: !0,
            alpha_to_coverage_enabled: false,
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let read = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("probe read"),
        layout: None,
        module: &module,
        entry_point: Some("read"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("probe"),
        layout: &read.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: masks.as_entire_binding(),
            },
        ],
    });
    let mut enc = d.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("probe"),
            color_attachments: &[bench_core::gpu::cleared(&view, wgpu::Color::TRANSPARENT)],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&raster);
        pass.set_vertex_buffer(0, vbuf.slice(..));
        pass.draw(0..verts.len() as u32, 0..1);
    }
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&read);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    gpu.queue.submit([enc.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(ProbeError::Render(e));
    }
    bench_core::gpu_util::read_vec::<u32>(gpu, &masks, (PROBE_W * PROBE_H) as usize)
        .map_err(ProbeError::ReadBack)
}

/// The `sample_positions` column for `samples`× MSAA on `gpu`: `standard`, `differs: …` or
/// `unverified: <why>`; probed once per adapter and sample count (cached).
pub fn sample_positions(gpu: &Gpu, samples: u32) -> String {
    if samples <= 1 {
        return "standard".into();
    }
    /// (adapter, backend, driver, samples) → verdict.
    type Cache = Mutex<HashMap<(String, String, String, u32), String>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let f = &gpu.facts;
    let key = (
        f.name.clone(),
        f.backend.clone(),
        f.driver_info.clone(),
        samples,
    );
    let cache = CACHE.get_or_init(Default::default);
    if let Some(v) = cache.lock().unwrap().get(&key) {
        return v.clone();
    }
    let v = match run_probe(gpu, samples) {
        Ok(masks) => probe_verdict(&masks, samples),
        Err(why) => format!("unverified: {why}"),
    };
    cache.lock().unwrap().insert(key, v.clone());
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_verdict_recognises_standard_reordered_and_moved_positions() {
        for s in [2, 4, 8] {
            let std = probe_expected(standard_positions(s));
            assert_eq!(probe_verdict(&std, s), "standard", "{s} samples");
            // The positions the probe reads back from standard masks are the standard ones.
            assert_eq!(probe_positions(&std, s), standard_positions(s));
        }
        // A GPU sampling 4× at a rotated grid is named with its positions.
        let moved = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];
        let v = probe_verdict(&probe_expected(&moved), 4);
        assert_eq!(
            v,
            "differs: (0.2500,0.2500) (0.7500,0.2500) (0.2500,0.7500) (0.7500,0.7500)"
        );
        // Every sample at the centre (no MSAA at all) is caught too.
        let v = probe_verdict(&probe_expected(&[(0.5, 0.5); 4]), 4);
        assert!(v.starts_with("differs: (0.5000,0.5000)"), "{v}");
    }
}
