//! What `bdp`, `bdp2` and `adp` share (Liu et al., "Multi-Fragment Effects on the GPU Using
//! Bucket Sort", GPU Pro ch. 1): the GPU frame ([`PreparedBucket`]) and the CPU twins of every
//! per-pixel rule in `bucket.wgsl` and the methods' WGSL (vello style: same names, same f32
//! arithmetic), which tests use to name the pixel and fragment that went wrong.
//!
//! Frame: a depth-range pre-pass (RG32Float, MAX blending of (−d, d)) → [adp: histogram pass +
//! equalisation] → routing pass(es) into K buckets on up to 8 RGBA32F attachments with MAX
//! blending → a compute resolve that walks the buckets nearest first through the effects fold.
//!
//! Effects (GPU Pro ch. 1 §1.6.2–1.6.3): for translucency and Fresnel ([`Fx`]) the buckets are
//! bound into pairs, as the chapter does: one channel keeps the linear view depth with the
//! facing in its lowest bit, the other the normal packed in 4 bytes (`packing.wgsl`,
//! octahedral 15:15), both MAX-blended, so where two fragments share a bucket (a collision,
//! counted as for colour) the pair may mix them: reported, not hidden.
//!
//! Collisions are counted exactly, per pixel, as (true fragments) − (fragments captured): the
//! captured count comes from the resolve, the true count from an untimed fragment-counter pass
//! (one atomicAdd per fragment) run in `readback`, so the timed frame carries no counter. Tests
//! check this GPU count against the CPU twin routing the reference fragment lists.

use crate::effects::{Effect, EffectConfig, FOLD_STATE_BYTES};
use crate::methods::shared::packing::PACKING_WGSL;
use bench_core::axes::{Axis, Point};
use bench_core::bind::{
    pipeline_layout, render_pipeline, Bindings, Kind as B, Raster, Res, FC, FLOAT,
};
use bench_core::gpu_util::{compute_pipeline, read_vec, STORAGE_RW};
use bench_core::record::{cols, Flag};
use bench_core::study::InvalidPoint;

use crate::methods::{Capture, Expected, FrameStats};
use bench_core::gpu::Gpu;
use bench_core::gpu_scene::{AllocCounter, Attrs, GpuScene};
use bench_core::timing::GpuTimer;
use bench_core::Result;
use mfx_reference::FragmentLists;

const WGSL: &str = include_str!("bucket.wgsl");
const FOLD_WGSL: &str = include_str!("../../../effects/fold.wgsl");
const SLOT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const RANGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
/// Float channels one routing pass can write: 8 attachments × 4 channels.
pub const MAX_CHANNELS: u32 = 32;
const MIN_NORMAL_BITS: u32 = 0x0080_0000;
/// std430 size of `FoldState` (vec4, vec4, u32, u32, padded to 16).
const PASS_STRIDE: u64 = 256;

/// Which bucket method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// BDP: uniform sub-intervals, one pass; `paired` keeps nearest and farthest per bucket.
    Uniform { paired: bool },
    /// BDP2: uniform, a second pass keeps the next fragment of each bucket; `paired` (§1.4):
    /// both passes keep a bucket pair, pass 2 the nearest and farthest strictly inside pass 1's.
    TwoPass { paired: bool },
    /// ADP: histogram-equalised sub-intervals, passes of K buckets; `paired` (§1.5): each
    /// occupied bin's bucket pair keeps its nearest and farthest fragment.
    Adaptive { hist_bins: u32, paired: bool },
    /// Multi-pass BDP (§1.4's loop): bucket pairs, each pass keeping the nearest and farthest
    /// strictly inside the previous pass's, until an occlusion query counts no fragment or
    /// `max_passes` passes have run.
    UntilCaptured { max_passes: u32 },
}

#[derive(Clone, Copy, Debug)]
pub struct Config {
    pub kind: Kind,
    /// Buckets per pass (K).
    pub buckets: u32,
}

impl Config {
    /// Float channels per routing pass.
    pub fn channels(&self) -> u32 {
        if self.paired() {
            2 * self.buckets
        } else {
            self.buckets
        }
    }
    /// Whether each bucket is a (nearest, farthest) pair of channels.
    pub fn paired(&self) -> bool {
        match self.kind {
            Kind::Uniform { paired } | Kind::TwoPass { paired } => paired,
            Kind::Adaptive { paired, .. } => paired,
            Kind::UntilCaptured { .. } => true,
        }
    }
    pub fn attachments(&self) -> u32 {
        self.channels().div_ceil(4)
    }
    /// Channels per pass when the buckets hold (depth, normal) pairs for effects.
    fn channels_fx(&self, fx: bool) -> u32 {
        if fx {
            2 * self.buckets
        } else {
            self.channels()
        }
    }
    fn attachments_fx(&self, fx: bool) -> u32 {
        self.channels_fx(fx).div_ceil(4)
    }
    fn mode(&self) -> u32 {
        match self.kind {
            Kind::Uniform { paired: false } => 0,
            Kind::Uniform { paired: true } => 1,
            Kind::TwoPass { paired: false } => 2,
            Kind::Adaptive { paired: false, .. } => 3,
            Kind::TwoPass { paired: true } => 4,
            Kind::Adaptive { paired: true, .. } => 5,
            Kind::UntilCaptured { .. } => 6,
        }
    }
    fn hist_bins(&self) -> u32 {
        match self.kind {
            Kind::Adaptive { hist_bins, .. } => hist_bins,
            _ => 32,
        }
    }
    /// Most routing passes a frame may need (adp: every bin occupied).
    pub fn max_passes(&self) -> u32 {
        match self.kind {
            Kind::Adaptive { hist_bins, .. } => hist_bins.div_ceil(self.buckets),
            Kind::UntilCaptured { max_passes } => max_passes,
            _ => 1,
        }
    }
}

/// Buckets per pixel per pass, shared by the bucket methods.
pub const BUCKET_COUNT: Axis = Axis::int(
    cols::BUCKET_COUNT,
    "buckets per pixel per pass (one float channel each, two when paired)",
    16,
    1,
    MAX_CHANNELS as i64,
);

/// `bucket_count`, checked against the channels one pass has.
pub fn buckets(point: &Point, paired: bool) -> std::result::Result<u32, InvalidPoint> {
    let k = point.int(&BUCKET_COUNT) as u32;
    let channels = if paired { 2 * k } else { k };
    if channels > MAX_CHANNELS {
        return Err(InvalidPoint::value(
            BUCKET_COUNT.name(),
            format!(
                "{k}{}",
                if paired {
                    " paired (2 channels per bucket)"
                } else {
                    ""
                }
            ),
            format!(
                "needs {channels} float channels; one pass has {MAX_CHANNELS} (8 attachments × 4)"
            ),
        ));
    }
    Ok(k)
}

/// `bucket_pairing` of `bdp2` and `adp` (GPU Pro ch. 1 §1.4, §1.5: bucket pairs). Free text with
/// no default, checked by [`pairing_of`] (each method's `validate`, before any GPU work): a suite
/// that does not name it keeps its rows' empty cell and mfx's single buckets.
pub const PAIRING_TEXT: Axis = Axis::text(
    cols::BUCKET_PAIRING,
    "single (unset: one fragment per bucket per pass) | paired (each bucket a pair keeping its nearest and farthest fragment, 2 channels: GPU Pro ch. 1 §1.4 for bdp2, §1.5 for adp)",
    None,
);

/// Whether the point asks for bucket pairs ([`PAIRING_TEXT`]), or the error naming the axis.
pub fn pairing_of(point: &Point) -> std::result::Result<bool, InvalidPoint> {
    match point.get(PAIRING_TEXT.name()) {
        None => Ok(false),
        Some(scenarios::ParamValue::Str(s)) if s == "single" => Ok(false),
        Some(scenarios::ParamValue::Str(s)) if s == "paired" => Ok(true),
        Some(v) => Err(InvalidPoint::value(
            PAIRING_TEXT.name(),
            v,
            "must be one of single, paired",
        )),
    }
}

/// What the depth-range pre-pass draws. GPU Pro ch. 1 §1.3: "a bounding box or a coarse visual
/// hull can be first rendered to approximate the depth range [zNear, zFar] per pixel"; §1.5:
/// "approximating the depth range per pixel by rendering the bounding box of the scene". `mesh`
/// (every triangle: the exact per-pixel range, one more full geometry pass) is mfx's earlier
/// choice, kept as the default so the suites that do not name the axis keep their rows.
pub const RANGE_PASS: Axis = Axis::choice(
    cols::RANGE_PASS,
    "what the depth-range pre-pass draws: mesh (every triangle) | bounding_box (the scene's axis-aligned box, §1.3)",
    "mesh",
    &["mesh", "bounding_box"],
);

/// The point's [`RANGE_PASS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RangePass {
    #[default]
    Mesh,
    BoundingBox,
}

impl RangePass {
    pub fn read(point: &Point) -> RangePass {
        match point.choice(&RANGE_PASS).as_str() {
            "bounding_box" => RangePass::BoundingBox,
            _ => RangePass::Mesh,
        }
    }
}

/// The scene's axis-aligned box, padded outward by 10⁻³ of its largest extent (at least 10⁻⁶):
/// a mesh edge lying in a box face then never shares the box's silhouette edge, so a pixel
/// centre covered by a fragment is always covered by the box (the rasterizer's edge rule could
/// otherwise split them). Padding only widens the range, which stays a bound.
pub fn padded_box(positions: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in positions {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    if positions.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f32, f32::max);
    let pad = (extent * 1e-3).max(1e-6);
    (lo.map(|x| x - pad), hi.map(|x| x + pad))
}

/// The box's eight corners, corner i taking hi on axis a where bit a of i is set.
fn box_corners(lo: [f32; 3], hi: [f32; 3]) -> [[f32; 3]; 8] {
    std::array::from_fn(|i| std::array::from_fn(|a| if (i >> a) & 1 == 1 { hi[a] } else { lo[a] }))
}

/// The box's six faces as corner quads (indices into [`box_corners`]).
const BOX_FACES: [[usize; 4]; 6] = [
    [0, 2, 6, 4],
    [1, 5, 7, 3],
    [0, 4, 5, 1],
    [2, 3, 7, 6],
    [0, 1, 3, 2],
    [4, 6, 7, 5],
];

/// The box's 12 triangles (36 vertices), drawn unculled so each pixel gets its front and back.
pub fn box_triangles(lo: [f32; 3], hi: [f32; 3]) -> Vec<[f32; 3]> {
    let c = box_corners(lo, hi);
    BOX_FACES
        .iter()
        .flat_map(|f| [f[0], f[1], f[2], f[0], f[2], f[3]])
        .map(|i| c[i])
        .collect()
}

/// The box's faces as quads (for the CPU reference of its per-pixel range).
pub fn box_quads(lo: [f32; 3], hi: [f32; 3]) -> Vec<[[f32; 3]; 4]> {
    let c = box_corners(lo, hi);
    BOX_FACES.iter().map(|f| f.map(|i| c[i])).collect()
}

/// Whether a box corner lies outside the near or far plane (w ≤ 0 or window depth outside
/// [0, 1]): the clipped box would then miss the near or far end of some pixels' range, so the
/// frame uses the whole [0, 1] range instead (a bound still, no longer a tight one).
pub fn box_clipped(clip_from_world: &[[f32; 4]; 4], lo: [f32; 3], hi: [f32; 3]) -> bool {
    box_corners(lo, hi).iter().any(|p| {
        let v = [p[0], p[1], p[2], 1.0];
        let row = |r: usize| (0..4).map(|c| clip_from_world[c][r] * v[c]).sum::<f32>();
        let (z, w) = (row(2), row(3));
        w.is_nan() || w <= 0.0 || z < 0.0 || z > w
    })
}

/// Which effect a bucket method computes: transparency on packed colour, or translucency /
/// Fresnel on (depth, normal) bucket pairs (`pairs`); csg and dof are not offered.
#[derive(Clone, Copy, Debug)]
pub struct Fx {
    pub effect: EffectConfig,
    pub pairs: bool,
}

impl Fx {
    /// The point's effect, or why a bucket method cannot compute it.
    pub fn read(point: &Point) -> std::result::Result<Fx, InvalidPoint> {
        let effect = EffectConfig::from_point(point)?;
        let pairs = match effect.effect {
            Effect::Transparency => false,
            Effect::Translucency | Effect::Fresnel => true,
            e => {
                return Err(InvalidPoint::combination(format!(
                    "bucket methods fold transparency, translucency and fresnel (the chapter's effects): {} needs an object id or colour beside the depth, which a MAX-blended bucket pair cannot keep together",
                    e.name()
                )))
            }
        };
        Ok(Fx { effect, pairs })
    }
}

/// `bucket_count` for a point's effect: (depth, normal) pairs take two channels per bucket.
pub fn buckets_fx(point: &Point, paired: bool) -> std::result::Result<(u32, Fx), InvalidPoint> {
    let fx = Fx::read(point)?;
    if fx.pairs && paired {
        return Err(InvalidPoint::combination("bucket_pairing = paired keeps near and far colour in a bucket's two channels; translucency and fresnel use them for (depth, normal)"));
    }
    let k = point.int(&BUCKET_COUNT) as u32;
    if fx.pairs && 2 * k > MAX_CHANNELS {
        return Err(InvalidPoint::value(
            BUCKET_COUNT.name(),
            format!("{k} with {}", fx.effect.effect.name()),
            format!(
                "needs {} float channels ((depth, normal) per bucket); one pass has {MAX_CHANNELS} (8 attachments × 4)",
                2 * k
            ),
        ));
    }
    let k = buckets(point, paired)?;
    Ok((k, fx))
}

/// What every bucket method checks: blendable RGBA32F/RG32F and enough attachments.
pub fn supports_targets(
    gpu: &Gpu,
    cfg: &Config,
) -> std::result::Result<(), bench_core::Unsupported> {
    supports_targets_fx(gpu, cfg, false)
}

/// As [`supports_targets`], for (depth, normal) pairs when `fx`.
pub fn supports_targets_fx(
    gpu: &Gpu,
    cfg: &Config,
    fx: bool,
) -> std::result::Result<(), bench_core::Unsupported> {
    if !gpu.has(wgpu::Features::FLOAT32_BLENDABLE) {
        return Err("adapter lacks FLOAT32_BLENDABLE (MAX blending on RGBA32F/RG32F)".into());
    }
    for f in [SLOT_FORMAT, RANGE_FORMAT] {
        if !gpu.renderable(f) {
            return Err(format!("{f:?} is not renderable on this adapter").into());
        }
    }
    let n = cfg.attachments_fx(fx);
    if n > gpu.limits.max_color_attachments {
        return Err(format!(
            "{n} colour attachments needed, {} allows {}",
            gpu.profile.who(),
            gpu.limits.max_color_attachments
        )
        .into());
    }
    if n * 16 > gpu.limits.max_color_attachment_bytes_per_sample {
        return Err(format!(
            "{} bytes per sample needed, {} allows {}",
            n * 16,
            gpu.profile.who(),
            gpu.limits.max_color_attachment_bytes_per_sample
        )
        .into());
    }
    Ok(())
}

/// What `bdp`, `bdp2` and `adp` share as [`crate::methods::Method`]s: the point's [`Config`]
/// and [`Fx`] (each method's own rules), the method's WGSL, and from those the features, the
/// adapter check and the prepared frame, written once.
pub struct Spec {
    pub config: fn(&Point) -> std::result::Result<Config, InvalidPoint>,
    pub fx: fn(&Point) -> std::result::Result<Fx, InvalidPoint>,
    pub wgsl: &'static str,
}

impl Spec {
    /// Every bucket method MAX-blends 32-bit float targets.
    pub fn required_features(&self) -> wgpu::Features {
        wgpu::Features::FLOAT32_BLENDABLE
    }

    /// The point's own refusals (config, effect), then the adapter's targets.
    pub fn supports(
        &self,
        gpu: &Gpu,
        point: &Point,
    ) -> std::result::Result<(), bench_core::Unsupported> {
        let fx = (self.fx)(point)?;
        supports_targets_fx(gpu, &(self.config)(point)?, fx.pairs)
    }

    pub fn prepare(
        &self,
        gpu: &Gpu,
        scene: &GpuScene,
        point: &Point,
    ) -> Result<Box<dyn crate::methods::Prepared>> {
        let cfg = (self.config)(point)?;
        let fx = (self.fx)(point)?;
        Ok(Box::new(PreparedBucket::with_range(
            gpu,
            scene,
            cfg,
            self.wgsl,
            fx,
            RangePass::read(point),
        )?))
    }
}

// ---------------------------------------------------------------------------------------------
// CPU twins (same names and f32 arithmetic as the WGSL).

/// Nearness-relative position of window depth `d` in [zmin, zmax]: 0 nearest, 1 farthest.
pub fn rel_position(d: f32, zmin: f32, zmax: f32, reversed: bool) -> f32 {
    let span = zmax - zmin;
    if span.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return 0.0;
    }
    if reversed {
        ((zmax - d) / span).clamp(0.0, 1.0)
    } else {
        ((d - zmin) / span).clamp(0.0, 1.0)
    }
}

pub fn uniform_bucket(t: f32, k: u32) -> u32 {
    ((t * k as f32) as u32).min(k - 1)
}

pub fn bucket_key(t: f32, b: u32, k: u32) -> u32 {
    let r = t * k as f32 - b as f32;
    ((r.max(0.0) * 127.0) as u32).min(126)
}

pub fn adp_bin(t: f32, bins: u32) -> u32 {
    ((t * bins as f32) as u32).min(bins - 1)
}

fn q(x: f32, levels: f32) -> u32 {
    (x.clamp(0.0, 1.0) * levels + 0.5).floor() as u32
}

/// RGBA → a positive normal f32 (R, G, B 7 bits, alpha 0..1015): the payload p < 127·2^24 sits at
/// bits p + 2^23, so the value lies in [f32::MIN_POSITIVE, f32::MAX] — never 0 (empty),
/// denormal, Inf or NaN — and MAX blending orders it like p. Quantisation: RGB ±1/254, A ±1/2030.
pub fn pack_color(c: [f32; 4]) -> f32 {
    let p =
        (q(c[3], 1015.0) << 21) | (q(c[0], 127.0) << 14) | (q(c[1], 127.0) << 7) | q(c[2], 127.0);
    f32::from_bits(p + MIN_NORMAL_BITS)
}

pub fn unpack_color(v: f32) -> [f32; 4] {
    let p = v.to_bits() - MIN_NORMAL_BITS;
    [
        ((p >> 14) & 127) as f32 / 127.0,
        ((p >> 7) & 127) as f32 / 127.0,
        (p & 127) as f32 / 127.0,
        (p >> 21) as f32 / 1015.0,
    ]
}

/// Order key 0..126 above RGBA at 6 bits each (±1/126): MAX keeps the largest key with its colour.
pub fn pack_keyed(key: u32, c: [f32; 4]) -> f32 {
    let p = (key.min(126) << 24)
        | (q(c[0], 63.0) << 18)
        | (q(c[1], 63.0) << 12)
        | (q(c[2], 63.0) << 6)
        | q(c[3], 63.0);
    f32::from_bits(p + MIN_NORMAL_BITS)
}

pub fn keyed_key(v: f32) -> u32 {
    (v.to_bits() - MIN_NORMAL_BITS) >> 24
}

pub fn keyed_color(v: f32) -> [f32; 4] {
    let p = v.to_bits() - MIN_NORMAL_BITS;
    [
        ((p >> 18) & 63) as f32 / 63.0,
        ((p >> 12) & 63) as f32 / 63.0,
        ((p >> 6) & 63) as f32 / 63.0,
        (p & 63) as f32 / 63.0,
    ]
}

/// ADP equalisation of one pixel: the bins of ranks pass·K .. pass·K + K among the occupied
/// bins of `hist` (words of 32 bins, bin 0 nearest), `u32::MAX` where there are fewer.
pub fn adp_equalise(hist: &[u32], k: u32, pass: u32) -> Vec<u32> {
    let first = (pass * k) as usize;
    let occupied =
        (0..hist.len() as u32 * 32).filter(|&b| hist[(b / 32) as usize] >> (b % 32) & 1 == 1);
    let mut out: Vec<u32> = occupied.skip(first).take(k as usize).collect();
    out.resize(k as usize, u32::MAX);
    out
}

/// One reference fragment as the GPU routes it.
#[derive(Clone, Copy, Debug)]
pub struct Routed {
    /// Index in the pixel's reference list (nearest first).
    pub index: usize,
    /// Nearness position t in [0, 1].
    pub t: f32,
    /// Bucket (bdp, bdp2) or occupied histogram bin (adp).
    pub bucket: u32,
    /// In-bucket key (paired, bdp2).
    pub key: u32,
    /// Distance of t·K (or t·bins) from the nearest bucket boundary, in buckets: a small
    /// margin means f32 rounding on the GPU could route it differently.
    pub margin: f32,
}

/// The routing twin for one pixel of the reference: zmin/zmax are the pixel's reference
/// extremes in f32, exactly what the pre-pass stores.
pub fn route_pixel(
    cfg: &Config,
    frags: &[mfx_reference::RefFragment],
    reversed: bool,
) -> Vec<Routed> {
    route_pixel_in(cfg, frags, reversed, None)
}

/// As [`route_pixel`], with the pixel's (zmin, zmax) given (the bounding-box range pass) instead
/// of the fragments' own extremes.
pub fn route_pixel_in(
    cfg: &Config,
    frags: &[mfx_reference::RefFragment],
    reversed: bool,
    range: Option<(f32, f32)>,
) -> Vec<Routed> {
    if frags.is_empty() {
        return Vec::new();
    }
    let ds: Vec<f32> = frags.iter().map(|f| f.depth as f32).collect();
    let (zmin, zmax) = range.unwrap_or_else(|| {
        (
            ds.iter().copied().fold(f32::INFINITY, f32::min),
            ds.iter().copied().fold(f32::NEG_INFINITY, f32::max),
        )
    });
    ds.iter()
        .enumerate()
        .map(|(index, &d)| {
            let t = rel_position(d, zmin, zmax, reversed);
            let (bucket, key, scale) = match cfg.kind {
                // The key inside the bin orders a paired bin's two fragments (§1.5's pairs).
                Kind::Adaptive { hist_bins, .. } => {
                    let b = adp_bin(t, hist_bins);
                    (b, bucket_key(t, b, hist_bins), hist_bins as f32)
                }
                _ => {
                    let b = uniform_bucket(t, cfg.buckets);
                    (b, bucket_key(t, b, cfg.buckets), cfg.buckets as f32)
                }
            };
            let x = t * scale;
            let margin = if x <= 0.0 || x >= scale {
                f32::INFINITY
            } else {
                (x - x.round()).abs()
            };
            Routed {
                index,
                t,
                bucket,
                key,
                margin,
            }
        })
        .collect()
}

/// Fragments the method captures in one pixel, from the twin's routing (see the WGSL resolve).
pub fn captured_in_pixel(cfg: &Config, routed: &[Routed]) -> u32 {
    use std::collections::BTreeMap;
    let mut per_bucket: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for r in routed {
        per_bucket.entry(r.bucket).or_default().push(r.key);
    }
    per_bucket
        .values()
        .map(|keys| match cfg.kind {
            Kind::Uniform { paired: false } | Kind::Adaptive { paired: false, .. } => 1,
            Kind::Uniform { paired: true } | Kind::Adaptive { paired: true, .. } => {
                let lo = keys.iter().min().unwrap();
                let hi = keys.iter().max().unwrap();
                if lo == hi {
                    1
                } else {
                    2
                }
            }
            Kind::TwoPass { paired } => {
                // Single: the largest key, then the largest below it. Paired: the smallest and
                // largest key, then the smallest and largest strictly between them.
                let distinct: std::collections::BTreeSet<_> = keys.iter().collect();
                distinct.len().min(if paired { 4 } else { 2 }) as u32
            }
            // Two distinct keys a pass, the outermost first, until none is left.
            Kind::UntilCaptured { max_passes } => {
                let distinct: std::collections::BTreeSet<_> = keys.iter().collect();
                distinct.len().min(2 * max_passes as usize) as u32
            }
        })
        .sum()
}

/// The twin's per-pixel captured counts over a whole frame.
pub fn twin_captured(cfg: &Config, lists: &FragmentLists) -> Vec<u32> {
    (0..lists.pixels())
        .map(|p| captured_in_pixel(cfg, &route_pixel(cfg, lists.pixel(p), lists.reversed_z)))
        .collect()
}

/// The twin's collision count: true fragments not individually captured.
pub fn twin_collisions(cfg: &Config, lists: &FragmentLists) -> u64 {
    let cap = twin_captured(cfg, lists);
    (0..lists.pixels())
        .map(|p| lists.pixel(p).len() as u64 - cap[p] as u64)
        .sum()
}

// ---------------------------------------------------------------------------------------------
// The GPU side.

/// `struct BucketOut` and `emit` for `n` attachments: writes v0 into channel ch0, v1 into ch1,
/// 0 into every other channel (MAX blending then keeps the largest per channel).
fn outputs_wgsl(n: u32) -> String {
    let mut s = String::from("struct BucketOut {\n");
    for i in 0..n {
        s += &format!("    @location({i}) o{i}: vec4<f32>,\n");
    }
    s += "};\n\nfn lane(base: u32, ch0: u32, v0: f32, ch1: u32, v1: f32) -> vec4<f32> {\n";
    s += "    let c = vec4<u32>(base, base + 1u, base + 2u, base + 3u);\n";
    s += "    return select(vec4<f32>(0.0), vec4<f32>(v0), c == vec4<u32>(ch0)) + select(vec4<f32>(0.0), vec4<f32>(v1), c == vec4<u32>(ch1));\n}\n\n";
    s += "fn emit(ch0: u32, v0: f32, ch1: u32, v1: f32) -> BucketOut {\n    var o: BucketOut;\n";
    for i in 0..n {
        s += &format!("    o.o{i} = lane({}u, ch0, v0, ch1, v1);\n", 4 * i);
    }
    s += "    return o;\n}\n";
    s
}

fn max_blend() -> wgpu::BlendState {
    let c = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Max,
    };
    wgpu::BlendState { color: c, alpha: c }
}

/// An RGBA32F 2D array: one layer per attachment; layer views for rendering, an array view for reading.
struct Slots {
    layers: Vec<wgpu::TextureView>,
    /// Kept alive for the bind group.
    _array: wgpu::TextureView,
    bind: wgpu::BindGroup,
}

pub struct PreparedBucket {
    cfg: Config,
    bounds: wgpu::RenderPipeline,
    route: wgpu::RenderPipeline,
    second: Option<wgpu::RenderPipeline>,
    hist_pass: Option<wgpu::RenderPipeline>,
    equalise: Option<wgpu::ComputePipeline>,
    gather: Option<wgpu::ComputePipeline>,
    count: wgpu::RenderPipeline,
    resolve: wgpu::ComputePipeline,
    cam_bind: wgpu::BindGroup,
    main_bind: wgpu::BindGroup,
    range_view: wgpu::TextureView,
    slots_a: Slots,
    slots_b: Option<Slots>,
    frag_count: wgpu::Buffer,
    hist: wgpu::Buffer,
    adp_bounds: wgpu::Buffer,
    occupied_max: wgpu::Buffer,
    occ_read: wgpu::Buffer,
    accum: wgpu::Buffer,
    counts: wgpu::Buffer,
    /// Routing passes of the last frame (adp: ⌈max occupied bins / K⌉).
    pub last_passes: u32,
    /// `range_pass = bounding_box`: the box drawn instead of the mesh.
    range_box: Option<RangeBox>,
    /// Multi-pass BDP: the query that ends the loop.
    occlusion: Option<OcclusionQuery>,
    alloc: AllocCounter,
}

/// One occlusion query, its resolve buffer and its read-back buffer (as depth peeling's).
struct OcclusionQuery {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
}

impl OcclusionQuery {
    fn new(gpu: &Gpu) -> OcclusionQuery {
        let d = &gpu.device;
        let set = d.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("bdpn occlusion"),
            ty: wgpu::QueryType::Occlusion,
            count: 1,
        });
        let resolve = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bdpn occlusion resolve"),
            size: 256,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bdpn occlusion read"),
            size: 8,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        OcclusionQuery { set, resolve, read }
    }
}

/// The scene's padded bounding box as 36 vertices, and whether it crosses the near or far plane.
struct RangeBox {
    vertices: wgpu::Buffer,
    clipped: bool,
}

impl RangeBox {
    /// Reads the scene's positions back (once, untimed) and builds the box.
    fn new(gpu: &Gpu, scene: &GpuScene, alloc: &mut AllocCounter) -> Result<RangeBox> {
        use wgpu::util::DeviceExt;
        let n = (scene.positions.size() / 12) as usize;
        let positions = read_vec::<[f32; 3]>(gpu, &scene.positions, n)?;
        let (lo, hi) = padded_box(&positions);
        let tris = box_triangles(lo, hi);
        let vertices = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("bucket range box"),
                contents: bytemuck::cast_slice(&tris),
                usage: wgpu::BufferUsages::VERTEX,
            });
        alloc.bytes += vertices.size();
        let clipped = box_clipped(&scene.camera_data.clip_from_world, lo, hi);
        Ok(RangeBox { vertices, clipped })
    }
}

impl PreparedBucket {
    /// `method_wgsl` holds the method's fragment entry points (`fs_route`, and `fs_first` /
    /// `fs_second` for bdp2, `fs_hist` / `equalise` for adp).
    pub fn new(
        gpu: &Gpu,
        scene: &GpuScene,
        cfg: Config,
        method_wgsl: &str,
    ) -> Result<PreparedBucket> {
        let fx = Fx {
            effect: EffectConfig::default(),
            pairs: false,
        };
        Self::new_fx(gpu, scene, cfg, method_wgsl, fx)
    }

    /// As [`PreparedBucket::new`], folding `fx`'s effect (pairs: (depth, normal) per bucket).
    pub fn new_fx(
        gpu: &Gpu,
        scene: &GpuScene,
        cfg: Config,
        method_wgsl: &str,
        fx: Fx,
    ) -> Result<PreparedBucket> {
        Self::with_range(gpu, scene, cfg, method_wgsl, fx, RangePass::Mesh)
    }

    /// As [`PreparedBucket::new_fx`], the depth range drawn from `range`.
    pub fn with_range(
        gpu: &Gpu,
        scene: &GpuScene,
        cfg: Config,
        method_wgsl: &str,
        fx: Fx,
        range: RangePass,
    ) -> Result<PreparedBucket> {
        let (w, h) = (scene.width, scene.height);
        let px = w as u64 * h as u64;
        let attachments = cfg.attachments_fx(fx.pairs);
        let body = format!(
            "{PACKING_WGSL}\n{FOLD_WGSL}\n{WGSL}\n{}\n{method_wgsl}",
            outputs_wgsl(attachments)
        );
        let module = bench_core::gpu_util::shader(gpu, "bucket", &body);
        // Group 0 of the depth-range pass; group 0 of every other pass (binding 2: this pass's
        // slice of `pass_info`; 3..=9: counter, histogram, bounds, occupied max, fold states,
        // accumulation, counts); the slot arrays (groups 1 and 2).
        let cam = Bindings::seq(gpu, "bucket camera", FC, &[B::Camera]);
        let mut rows = vec![B::Camera, B::Texture(FLOAT), B::UniformDynamic(16)];
        rows.extend([B::Storage; 7]);
        let main = Bindings::seq(gpu, "bucket main", FC, &rows);
        let arr = Bindings::seq(gpu, "bucket slots", FC, &[B::TextureArray(FLOAT)]);
        let cam_layout = pipeline_layout(gpu, "bucket bounds", &[&cam.layout]);
        let main_layout = pipeline_layout(gpu, "bucket main", &[&main.layout]);
        let second_layout = pipeline_layout(gpu, "bucket second", &[&main.layout, &arr.layout]);
        let resolve_layout = pipeline_layout(
            gpu,
            "bucket resolve",
            &[&main.layout, &arr.layout, &arr.layout],
        );

        let layouts = [&cam_layout, &main_layout, &second_layout, &resolve_layout];
        let declared = declared_constants(&cfg, &fx, &body);
        let Passes {
            bounds,
            count,
            route,
            second,
            hist_pass,
            equalise,
            resolve,
            gather,
        } = Passes::new(gpu, &module, &declared, cfg, attachments, layouts);

        let mut alloc = AllocCounter::default();
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let range_view = alloc
            .texture(gpu, "bucket depth range", w, h, RANGE_FORMAT, usage)
            .create_view(&Default::default());
        let slots_a = Slots::new(gpu, &mut alloc, &arr, "bucket slots", (w, h), attachments);
        let slots_b =
            matches!(cfg.kind, Kind::TwoPass { .. } | Kind::UntilCaptured { .. }).then(|| {
                Slots::new(
                    gpu,
                    &mut alloc,
                    &arr,
                    "bdp2 second slots",
                    (w, h),
                    attachments,
                )
            });
        let b = Buffers::new(gpu, &mut alloc, &cfg, px);
        let range_box = match range {
            RangePass::Mesh => None,
            RangePass::BoundingBox => Some(RangeBox::new(gpu, scene, &mut alloc)?),
        };
        let cam_bind = cam.group(gpu, &[Res::Buf(&scene.camera)]);
        let main_bind = main.group(
            gpu,
            &[
                (&scene.camera).into(),
                (&range_view).into(),
                Res::Window(&b.pass_info, 16),
                (&b.frag_count).into(),
                (&b.hist).into(),
                (&b.adp_bounds).into(),
                (&b.occupied_max).into(),
                (&b.fold_states).into(),
                (&b.accum).into(),
                (&b.counts).into(),
            ],
        );
        Ok(PreparedBucket {
            cfg,
            bounds,
            route,
            second,
            hist_pass,
            equalise,
            gather,
            count,
            resolve,
            cam_bind,
            occlusion: matches!(cfg.kind, Kind::UntilCaptured { .. })
                .then(|| OcclusionQuery::new(gpu)),
            main_bind,
            range_view,
            slots_a,
            slots_b,
            frag_count: b.frag_count,
            hist: b.hist,
            adp_bounds: b.adp_bounds,
            occupied_max: b.occupied_max,
            occ_read: b.occ_read,
            accum: b.accum,
            counts: b.counts,
            last_passes: 0,
            range_box,
            alloc,
        })
    }

    fn pass_offset(p: u32) -> u32 {
        (p as u64 * PASS_STRIDE) as u32
    }

    fn slot_attachments(
        views: &[wgpu::TextureView],
    ) -> Vec<Option<wgpu::RenderPassColorAttachment<'_>>> {
        views
            .iter()
            .map(|v| {
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect()
    }

    /// A geometry pass of `pipeline` into `targets` (cleared to 0 = empty).
    #[allow(
        clippy::too_many_arguments,
        reason = "one geometry pass: encoder, scene, timer, pipeline, targets and bindings"
    )]
    fn geometry_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        label: &str,
        pipeline: &wgpu::RenderPipeline,
        targets: &[wgpu::TextureView],
        extra: Option<&wgpu::BindGroup>,
        pass_index: u32,
    ) {
        self.geometry_pass_counted(
            enc, scene, timer, label, pipeline, targets, extra, pass_index, None,
        );
    }

    /// As [`Self::geometry_pass`], counting the samples its fragments write into `occlusion`.
    #[allow(
        clippy::too_many_arguments,
        reason = "geometry_pass's arguments plus the occlusion query set"
    )]
    fn geometry_pass_counted(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        label: &str,
        pipeline: &wgpu::RenderPipeline,
        targets: &[wgpu::TextureView],
        extra: Option<&wgpu::BindGroup>,
        pass_index: u32,
        occlusion: Option<&wgpu::QuerySet>,
    ) {
        let att = Self::slot_attachments(targets);
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &att,
            depth_stencil_attachment: None,
            timestamp_writes: timer.render_pass(label),
            occlusion_query_set: occlusion,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.main_bind, &[Self::pass_offset(pass_index)]);
        if let Some(b) = extra {
            pass.set_bind_group(1, b, &[]);
        }
        if occlusion.is_some() {
            pass.begin_occlusion_query(0);
        }
        scene.draw(&mut pass, Attrs::ALL);
        if occlusion.is_some() {
            pass.end_occlusion_query();
        }
    }

    /// Multi-pass BDP (GPU Pro ch. 1 §1.4: "we can obtain accurate results by enabling the
    /// occlusion query and looping in the same way until all the fragments have been
    /// captured"). Pass p writes slots[p % 2] reading slots[(p − 1) % 2]; after each pass a
    /// compute gather copies its pairs into the per-pass store, so the resolve can walk every
    /// bucket dmin¹ ≤ dmin² ≤ … ≤ dmax² ≤ dmax¹ at the end (the fold runs nearest first and a
    /// bucket's far fragments come after all of its passes' near ones). Each pass after the
    /// first reads its query back before the next is encoded: one CPU round trip a pass, as
    /// depth peeling's. Returns (passes holding fragments, geometry passes drawn).
    fn frame_until_captured(
        &self,
        gpu: &Gpu,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        mut enc: wgpu::CommandEncoder,
    ) -> Result<(u32, u32)> {
        let (Some(second), Some(slots_b), Some(gather), Some(q)) =
            (&self.second, &self.slots_b, &self.gather, &self.occlusion)
        else {
            unreachable!("multi-pass BDP prepares its second pass, slots, gather and query");
        };
        let slots = [&self.slots_a, slots_b];
        let max_passes = self.cfg.max_passes();
        self.geometry_pass(
            &mut enc,
            scene,
            timer,
            "route",
            &self.route,
            &self.slots_a.layers,
            None,
            0,
        );
        self.compute_pass(&mut enc, scene, timer, "gather", gather, 0);
        let (mut filled, mut drawn) = (1, 1);
        while filled < max_passes {
            let p = filled;
            self.geometry_pass_counted(
                &mut enc,
                scene,
                timer,
                "peel",
                second,
                &slots[(p % 2) as usize].layers,
                Some(&slots[((p + 1) % 2) as usize].bind),
                p,
                Some(&q.set),
            );
            drawn += 1;
            enc.resolve_query_set(&q.set, 0..1, &q.resolve, 0);
            enc.copy_buffer_to_buffer(&q.resolve, 0, &q.read, 0, 8);
            gpu.queue.submit([enc.finish()]);
            let bytes = gpu.map_read(&q.read)?;
            enc = gpu.device.create_command_encoder(&Default::default());
            if u64::from_le_bytes(bytes[..8].try_into().unwrap()) == 0 {
                break;
            }
            self.compute_pass(&mut enc, scene, timer, "gather", gather, p);
            filled += 1;
        }
        // The resolve reads how many passes the store holds (stale passes of earlier frames
        // lie beyond it).
        gpu.queue
            .write_buffer(&self.occupied_max, 0, &filled.to_le_bytes());
        self.compute_pass(&mut enc, scene, timer, "resolve", &self.resolve, 0);
        gpu.queue.submit([enc.finish()]);
        Ok((filled, drawn))
    }

    fn compute_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        pass_index: u32,
    ) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: timer.compute_pass(label),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.main_bind, &[Self::pass_offset(pass_index)]);
        pass.set_bind_group(1, &self.slots_a.bind, &[]);
        let b = self.slots_b.as_ref().unwrap_or(&self.slots_a);
        pass.set_bind_group(2, &b.bind, &[]);
        pass.dispatch_workgroups(scene.width.div_ceil(8), scene.height.div_ceil(8), 1);
    }

    /// Routing pass `p` and its resolve (adp: equalisation first).
    fn route_and_resolve(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timer: &mut GpuTimer,
        p: u32,
    ) {
        if let Some(eq) = &self.equalise {
            self.compute_pass(enc, scene, timer, "equalise", eq, p);
        }
        self.geometry_pass(
            enc,
            scene,
            timer,
            "route",
            &self.route,
            &self.slots_a.layers,
            None,
            p,
        );
        if let (Some(second), Some(b)) = (&self.second, &self.slots_b) {
            self.geometry_pass(
                enc,
                scene,
                timer,
                "second",
                second,
                &b.layers,
                Some(&self.slots_a.bind),
                p,
            );
        }
        self.compute_pass(enc, scene, timer, "resolve", &self.resolve, p);
    }

    /// Reads the adp histogram (words per pixel) and the last pass's bounds (K per pixel).
    pub fn read_adp(&self, gpu: &Gpu, scene: &GpuScene) -> Result<(Vec<u32>, Vec<u32>)> {
        let n = scene.pixels();
        let words = (self.cfg.hist_bins() / 32) as usize;
        Ok((
            read_vec::<u32>(gpu, &self.hist, n * words)?,
            read_vec::<u32>(gpu, &self.adp_bounds, n * self.cfg.buckets as usize)?,
        ))
    }

    /// Runs the untimed fragment counter: true fragments per pixel as the GPU rasterizes them.
    pub fn count_fragments(&self, gpu: &Gpu, scene: &GpuScene) -> Result<Vec<u32>> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.frag_count, 0, None);
        {
            let att = [Some(wgpu::RenderPassColorAttachment {
                view: &self.slots_a.layers[0],
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })];
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("bucket count"),
                color_attachments: &att,
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.count);
            pass.set_bind_group(0, &self.main_bind, &[0]);
            scene.draw(&mut pass, Attrs::POSITION_ONLY);
        }
        gpu.queue.submit([enc.finish()]);
        read_vec::<u32>(gpu, &self.frag_count, scene.pixels())
    }
}

impl bench_core::timed::Timed for PreparedBucket {
    fn frame(&mut self, gpu: &Gpu, scene: &GpuScene, timer: &mut GpuTimer) -> Result<FrameStats> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        let mut stats = FrameStats::default();
        {
            // Below every (−d, d) with d in [0, 1]: an untouched pixel reads zmax < zmin. A box
            // that crosses the near or far plane is not drawn: every pixel takes [0, 1].
            let whole = self.range_box.as_ref().is_some_and(|b| b.clipped);
            let clear = if whole {
                wgpu::Color {
                    r: 0.0,
                    g: 1.0,
                    b: 0.0,
                    a: 0.0,
                }
            } else {
                wgpu::Color {
                    r: -2.0,
                    g: -2.0,
                    b: 0.0,
                    a: 0.0,
                }
            };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("depth range"),
                color_attachments: &[bench_core::gpu::cleared(&self.range_view, clear)],
                depth_stencil_attachment: None,
                timestamp_writes: timer.render_pass("depth range"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.bounds);
            pass.set_bind_group(0, &self.cam_bind, &[]);
            match &self.range_box {
                // The box is 12 triangles, not a pass over the scene's geometry.
                Some(b) if !whole => {
                    pass.set_vertex_buffer(0, b.vertices.slice(..));
                    pass.draw(0..36, 0..1);
                }
                Some(_) => {}
                None => {
                    scene.draw(&mut pass, Attrs::POSITION_ONLY);
                    stats.geometry_passes += 1;
                }
            }
        }
        if self.occlusion.is_some() {
            let (filled, drawn) = self.frame_until_captured(gpu, scene, timer, enc)?;
            stats.geometry_passes += drawn;
            self.last_passes = filled;
            stats.layers = filled;
            return Ok(stats);
        }
        if let Some(hist_pass) = &self.hist_pass {
            enc.clear_buffer(&self.hist, 0, None);
            enc.clear_buffer(&self.occupied_max, 0, None);
            self.geometry_pass(
                &mut enc,
                scene,
                timer,
                "histogram",
                hist_pass,
                &self.slots_a.layers[..1],
                None,
                0,
            );
            stats.geometry_passes += 1;
        }
        self.route_and_resolve(&mut enc, scene, timer, 0);
        stats.geometry_passes += if self.second.is_some() { 2 } else { 1 };
        let mut passes = 1;
        if self.equalise.is_some() {
            // The pass count depends on the most occupied bins of any pixel: one CPU round trip,
            // like depth peeling's occlusion query.
            enc.copy_buffer_to_buffer(&self.occupied_max, 0, &self.occ_read, 0, 4);
            gpu.queue.submit([enc.finish()]);
            let bytes = gpu.map_read(&self.occ_read)?;
            let max_occupied = u32::from_le_bytes(bytes[..4].try_into().unwrap());
            passes = max_occupied
                .div_ceil(self.cfg.buckets)
                .clamp(1, self.cfg.max_passes());
            enc = gpu.device.create_command_encoder(&Default::default());
            for p in 1..passes {
                self.route_and_resolve(&mut enc, scene, timer, p);
                stats.geometry_passes += 1;
            }
        }
        gpu.queue.submit([enc.finish()]);
        self.last_passes = passes;
        stats.layers = passes;
        Ok(stats)
    }

    fn bytes_allocated(&self) -> u64 {
        self.alloc.bytes
    }
}

impl crate::methods::Prepared for PreparedBucket {
    fn readback(&mut self, gpu: &Gpu, scene: &GpuScene) -> Result<Capture> {
        let n = scene.pixels();
        let mut cap = Capture::empty();
        cap.image = Some(read_vec::<[f32; 4]>(gpu, &self.accum, n)?);
        let counts = read_vec::<u32>(gpu, &self.counts, n)?;
        let truth = self.count_fragments(gpu, scene)?;
        let collisions: u64 = truth
            .iter()
            .zip(&counts)
            .map(|(&t, &c)| t.saturating_sub(c) as u64)
            .sum();
        cap.expected = Expected::All;
        cap.collision_fragments = Some(collisions);
        if collisions > 0 {
            cap.flag.add(Flag::Collision);
        }
        cap.counts = Some(counts);
        // The mesh range's note is unchanged (the CI suites' golden rows hold it).
        let range = match &self.range_box {
            None => "",
            Some(b) if b.clipped => {
                "; depth range [0, 1]: the scene's bounding box crosses the near or far plane"
            }
            Some(_) => "; depth range from the scene's bounding box",
        };
        cap.notes = format!(
            "collisions = GPU fragment count (untimed counter pass) − captured, per pixel; {} routing pass(es){range}",
            self.last_passes
        );
        Ok(cap)
    }
}

/// The frame's pipelines: depth range, fragment count, routing (bdp2: two passes; adp: the
/// histogram and equalisation too) and the resolve.
struct Passes {
    bounds: wgpu::RenderPipeline,
    count: wgpu::RenderPipeline,
    route: wgpu::RenderPipeline,
    second: Option<wgpu::RenderPipeline>,
    hist_pass: Option<wgpu::RenderPipeline>,
    equalise: Option<wgpu::ComputePipeline>,
    resolve: wgpu::ComputePipeline,
    /// Multi-pass BDP: copies a pass's pairs into the per-pass store (adp_bounds' buffer).
    gather: Option<wgpu::ComputePipeline>,
}

impl Passes {
    /// `layouts`: depth range, main, second (+ slots), resolve (+ both slot arrays).
    fn new(
        gpu: &Gpu,
        module: &wgpu::ShaderModule,
        declared: &[(&str, f64)],
        cfg: Config,
        attachments: u32,
        [cam_layout, main_layout, second_layout, resolve_layout]: [&wgpu::PipelineLayout; 4],
    ) -> Passes {
        let all_layouts: Vec<_> = GpuScene::layouts(Attrs::ALL)
            .into_iter()
            .map(Some)
            .collect();
        let pos_layouts: Vec<_> = GpuScene::layouts(Attrs::POSITION_ONLY)
            .into_iter()
            .map(Some)
            .collect();
        let slot_targets: Vec<_> = (0..attachments).map(|_| target(SLOT_FORMAT)).collect();
        let render = |label: &str,
                      pl: &wgpu::PipelineLayout,
                      vs: &str,
                      fs: &str,
                      targets: &[Option<wgpu::ColorTargetState>]| {
            let buffers = if vs == "vs_position" {
                &pos_layouts
            } else {
                &all_layouts
            };
            let constants = declared;
            let (module, depth, samples) = (module, None, 1);
            let r = Raster {
                module,
                vs,
                buffers,
                fs,
                targets,
                constants,
                depth,
                samples,
            };
            render_pipeline(gpu, label, pl, r)
        };
        // Passes that only touch storage still need a target; nothing is written to it.
        let silent = [Some(wgpu::ColorTargetState {
            format: SLOT_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::empty(),
        })];
        let (full, slots) = ("vs_full", &slot_targets[..]);
        let bounds = render(
            "bucket depth range",
            cam_layout,
            "vs_position",
            "fs_bounds",
            &[target(RANGE_FORMAT)],
        );
        let count = render(
            "bucket count",
            main_layout,
            "vs_position",
            "fs_count",
            &silent,
        );
        let (route, second, hist_pass) = match cfg.kind {
            Kind::Uniform { .. } => (
                render("bdp route", main_layout, full, "fs_route", slots),
                None,
                None,
            ),
            Kind::TwoPass { .. } | Kind::UntilCaptured { .. } => (
                render("bdp2 first", main_layout, full, "fs_first", slots),
                Some(render(
                    "bdp2 second",
                    second_layout,
                    full,
                    "fs_second",
                    slots,
                )),
                None,
            ),
            Kind::Adaptive { .. } => (
                render("adp route", main_layout, full, "fs_route", slots),
                None,
                Some(render(
                    "adp histogram",
                    main_layout,
                    full,
                    "fs_hist",
                    &silent,
                )),
            ),
        };
        let compute = |label: &str, pl: &wgpu::PipelineLayout, entry: &str| {
            compute_pipeline(gpu, label, pl, module, entry, declared, false)
        };
        let resolve = compute("bucket resolve", resolve_layout, "resolve");
        let equalise = matches!(cfg.kind, Kind::Adaptive { .. })
            .then(|| compute("adp equalise", main_layout, "equalise"));
        let gather = matches!(cfg.kind, Kind::UntilCaptured { .. })
            .then(|| compute("bdpn gather", resolve_layout, "gather"));
        Passes {
            bounds,
            count,
            route,
            second,
            hist_pass,
            equalise,
            resolve,
            gather,
        }
    }
}

/// A MAX-blended colour target of `format` (every routing and range pass).
fn target(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: Some(max_blend()),
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// The override constants of `cfg` and `fx` that `body` declares: every override a stage can
/// see must be known to it, so only those the module declares are passed.
fn declared_constants(cfg: &Config, fx: &Fx, body: &str) -> Vec<(&'static str, f64)> {
    let paired = cfg.kind == (Kind::Uniform { paired: true });
    let constants = [
        ("K", cfg.buckets as f64),
        ("MODE", cfg.mode() as f64),
        ("HIST_BINS", cfg.hist_bins() as f64),
        ("PAIRED", if paired { 1.0 } else { 0.0 }),
        ("FX", if fx.pairs { 1.0 } else { 0.0 }),
        ("MAX_PASSES", cfg.max_passes() as f64),
    ];
    constants
        .iter()
        .chain(&fx.effect.constants())
        .copied()
        .filter(|(n, _)| body.contains(&format!("override {n}")))
        .collect()
}

impl Slots {
    /// `layers` RGBA32F bucket attachments in one array texture, bound through `arr`.
    fn new(
        gpu: &Gpu,
        alloc: &mut AllocCounter,
        arr: &Bindings,
        label: &str,
        (w, h): (u32, u32),
        layers: u32,
    ) -> Slots {
        alloc.bytes += w as u64 * h as u64 * 16 * layers as u64;
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let tex = gpu.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SLOT_FORMAT,
            usage,
            view_formats: &[],
        });
        let layer_views = (0..layers)
            .map(|l| {
                tex.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: l,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let array = tex.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let bind = arr.group(gpu, &[Res::View(&array)]);
        Slots {
            layers: layer_views,
            _array: array,
            bind,
        }
    }
}

/// The per-pixel storage of main bindings 2..=9, and the occupied-max read-back.
struct Buffers {
    pass_info: wgpu::Buffer,
    frag_count: wgpu::Buffer,
    hist: wgpu::Buffer,
    adp_bounds: wgpu::Buffer,
    occupied_max: wgpu::Buffer,
    occ_read: wgpu::Buffer,
    fold_states: wgpu::Buffer,
    accum: wgpu::Buffer,
    counts: wgpu::Buffer,
}

impl Buffers {
    fn new(gpu: &Gpu, alloc: &mut AllocCounter, cfg: &Config, px: u64) -> Buffers {
        let st = STORAGE_RW;
        let adaptive = matches!(cfg.kind, Kind::Adaptive { .. });
        let until_captured = matches!(cfg.kind, Kind::UntilCaptured { .. });
        let frag_count = alloc.buffer(gpu, "bucket fragment counter", px * 4, st);
        let hist_bytes = if adaptive {
            px * (cfg.hist_bins() / 32) as u64 * 4
        } else {
            4
        };
        let hist = alloc.buffer(gpu, "adp histogram", hist_bytes, st);
        // adp: K bounds a pixel; multi-pass BDP: the per-pass store of K pairs a pass.
        let bounds_bytes = if adaptive {
            px * cfg.buckets as u64 * 4
        } else if until_captured {
            px * cfg.buckets as u64 * cfg.max_passes() as u64 * 2 * 4
        } else {
            4
        };
        let adp_bounds = alloc.buffer(gpu, "adp bounds", bounds_bytes, st);
        let occupied_max = alloc.buffer(gpu, "adp occupied max", 4, st);
        let occ_read = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("adp occupied read"),
            size: 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let fold_states = alloc.buffer(gpu, "bucket fold states", px * FOLD_STATE_BYTES, st);
        let accum = alloc.buffer(gpu, "bucket accum", px * 16, st);
        let counts = alloc.buffer(gpu, "bucket counts", px * 4, st);
        // One PASS_STRIDE slice per routing pass, its index in the first word.
        let passes = cfg.max_passes() as u64;
        let pass_data: Vec<u8> = (0..passes)
            .flat_map(|p| {
                let mut v = vec![0u8; PASS_STRIDE as usize];
                v[..4].copy_from_slice(&(p as u32).to_le_bytes());
                v
            })
            .collect();
        let pass_info = alloc.buffer(
            gpu,
            "bucket pass info",
            passes * PASS_STRIDE,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        gpu.queue.write_buffer(&pass_info, 0, &pass_data);
        Buffers {
            pass_info,
            frag_count,
            hist,
            adp_bounds,
            occupied_max,
            occ_read,
            fold_states,
            accum,
            counts,
        }
    }
}

#[cfg(test)]
mod range_tests;
#[cfg(test)]
pub(crate) mod testing;
#[cfg(test)]
mod tests;
