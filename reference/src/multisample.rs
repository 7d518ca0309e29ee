//! The multisampled reference: the same exact rasteriser at the sample positions a GPU uses for
//! 2×, 4× and 8× MSAA (Vulkan's standard sample locations), with the same fill rule at every
//! sample, and at twice the width and height for 2×2 supersampling. A pixel's ground truth is
//! the mean of its samples' exact composites (`aa::truth` applies an effect to each sample).
//!
//! Two views of the same samples, matching the two ways a GPU method captures them:
//! - per sample ([`sample_lists`]): each sample has its own depth-sorted list, depth and
//!   attributes interpolated at the sample (sample shading: one invocation per sample);
//! - per fragment with a coverage mask ([`coverage_lists`]): one entry per (pixel, triangle)
//!   that covers any sample, depth and attributes at the pixel centre (pixel-rate shading,
//!   nvpro's `OIT_COVERAGE_SHADING`); sample s composites the entries whose mask has bit s, in
//!   centre-depth order. It equals the per-sample truth wherever a pixel's order and colours do
//!   not change within the pixel (no intersection, no colour gradient across it).

use scenarios::Scene;

use super::raster::{rasterize_each, rasterize_with, Sampling, CENTRE};
use super::{composite, FragmentLists, RefFragment};

/// An `aa` value that is none of [`AaMode::NAMES`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("aa '{text}' is not one of {}", AaMode::NAMES.join(", "))]
pub struct UnknownAaMode {
    pub text: String,
}

/// How a pixel is antialiased: the `aa` axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AaMode {
    /// One sample at the pixel centre (every method's default).
    None,
    /// MSAA with 2, 4 or 8 samples at the standard positions.
    Msaa(u32),
    /// The image rendered at twice the width and height, each pixel the mean of its 2×2.
    Ssaa2x2,
}

impl AaMode {
    /// The `aa` axis values, in order.
    pub const NAMES: &'static [&'static str] = &["none", "msaa2", "msaa4", "msaa8", "ssaa2x2"];

    pub fn parse(s: &str) -> Result<AaMode, UnknownAaMode> {
        Ok(match s {
            "none" => AaMode::None,
            "msaa2" => AaMode::Msaa(2),
            "msaa4" => AaMode::Msaa(4),
            "msaa8" => AaMode::Msaa(8),
            "ssaa2x2" => AaMode::Ssaa2x2,
            other => {
                return Err(UnknownAaMode {
                    text: other.to_string(),
                })
            }
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            AaMode::None => "none",
            AaMode::Msaa(2) => "msaa2",
            AaMode::Msaa(4) => "msaa4",
            AaMode::Msaa(8) => "msaa8",
            AaMode::Msaa(_) => "msaa",
            AaMode::Ssaa2x2 => "ssaa2x2",
        }
    }

    /// Samples per output pixel (the `aa_samples` column): 1, S, or 4.
    pub fn samples(self) -> u32 {
        match self {
            AaMode::None => 1,
            AaMode::Msaa(s) => s,
            AaMode::Ssaa2x2 => 4,
        }
    }

    /// The sample count of the render targets (1 unless MSAA).
    pub fn msaa_samples(self) -> u32 {
        match self {
            AaMode::Msaa(s) => s,
            _ => 1,
        }
    }
}

/// How MSAA fragments are captured (the `aa_capture` axis).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AaCapture {
    /// Sample shading: coverage, depth and lists per sample (memory × samples); attributes
    /// where the driver interpolates them (the centre on lavapipe, see
    /// `gpu_util::per_sample_source`).
    Sample,
    /// Pixel-rate shading: one fragment per pixel with its coverage mask, attributes and depth
    /// at the pixel centre, resolved per sample.
    Coverage,
}

impl AaCapture {
    pub fn name(self) -> &'static str {
        match self {
            AaCapture::Sample => "sample",
            AaCapture::Coverage => "coverage",
        }
    }
}

/// Vulkan's standard sample locations (the spec's table, "Multisampling"), offsets within the
/// pixel with (0, 0) its top-left corner; index i is sample i. 1 sample: the centre. Every
/// offset is a multiple of 1/16, so it lies exactly on the 1/256 sub-pixel grid: coverage at a
/// sample is decided exactly, with the same top-left rule as at a centre.
pub fn standard_positions(samples: u32) -> &'static [(f64, f64)] {
    match samples {
        1 => &[(0.5, 0.5)],
        2 => &[(0.75, 0.75), (0.25, 0.25)],
        4 => &[
            (0.375, 0.125),
            (0.875, 0.375),
            (0.125, 0.625),
            (0.625, 0.875),
        ],
        8 => &[
            (0.5625, 0.3125),
            (0.4375, 0.6875),
            (0.8125, 0.5625),
            (0.3125, 0.1875),
            (0.1875, 0.8125),
            (0.0625, 0.4375),
            (0.6875, 0.9375),
            (0.9375, 0.0625),
        ],
        other => panic!("no standard sample locations for {other} samples (1, 2, 4, 8)"),
    }
}

/// Where a per-sample list interpolates its attributes.
#[derive(Clone, Copy)]
enum Attributes {
    /// At the sample, with depth (sample shading).
    AtSample,
    /// At the pixel centre, depth still at the sample: a driver that interpolates inputs at
    /// the centre (lavapipe; see `AaCapture::Sample`).
    AtCentre,
}

/// The sampling of one sample position `one[0]`: coverage and depth there, attributes where
/// `attributes` says.
fn at_sample(one: &[(f64, f64); 1], attributes: Attributes) -> Sampling<'_> {
    let pos = one[0];
    match attributes {
        Attributes::AtSample => Sampling {
            coverage: one,
            attributes: pos,
            depth: None,
        },
        Attributes::AtCentre => Sampling {
            coverage: one,
            attributes: CENTRE.attributes,
            depth: Some(pos),
        },
    }
}

/// The lists of every position in `positions` (index = position), in one traversal of the
/// scene (`rasterize_each`): exactly the lists of one pass per position, held at once.
fn lists_at(
    scene: &Scene,
    width: u32,
    height: u32,
    positions: &[(f64, f64)],
    attributes: Attributes,
) -> Vec<FragmentLists> {
    let one: Vec<[(f64, f64); 1]> = positions.iter().map(|&p| [p]).collect();
    let samplings: Vec<Sampling<'_>> = one.iter().map(|c| at_sample(c, attributes)).collect();
    rasterize_each(scene, width, height, &samplings)
        .into_iter()
        .map(|(lists, _)| lists)
        .collect()
}

/// The lists of one sample position `pos` of every pixel: coverage, depth and attributes at
/// `pos` (sample shading). At the centre this is [`super::rasterize`].
pub fn sample_list(scene: &Scene, width: u32, height: u32, pos: (f64, f64)) -> FragmentLists {
    rasterize_with(
        scene,
        width,
        height,
        at_sample(&[pos], Attributes::AtSample),
    )
    .0
}

/// The lists of sample position `pos` with coverage and depth there and attributes at the
/// pixel centre: what a per-sample capture shades when its driver interpolates inputs at the
/// centre (lavapipe; see `AaCapture::Sample`).
pub fn sample_list_centre_attributes(
    scene: &Scene,
    width: u32,
    height: u32,
    pos: (f64, f64),
) -> FragmentLists {
    rasterize_with(
        scene,
        width,
        height,
        at_sample(&[pos], Attributes::AtCentre),
    )
    .0
}

/// [`sample_list`] of every position in `positions` (index = position), in one traversal of
/// the scene (`rasterize_each`): exactly the lists of one pass per position, held at once.
pub fn sample_lists_at(
    scene: &Scene,
    width: u32,
    height: u32,
    positions: &[(f64, f64)],
) -> Vec<FragmentLists> {
    lists_at(scene, width, height, positions, Attributes::AtSample)
}

/// [`sample_list_centre_attributes`] of every position in `positions`, in one traversal.
pub fn sample_lists_centre_attributes(
    scene: &Scene,
    width: u32,
    height: u32,
    positions: &[(f64, f64)],
) -> Vec<FragmentLists> {
    lists_at(scene, width, height, positions, Attributes::AtCentre)
}

/// One list set per standard sample position (index = sample index), in one traversal.
pub fn sample_lists(scene: &Scene, width: u32, height: u32, samples: u32) -> Vec<FragmentLists> {
    sample_lists_at(scene, width, height, standard_positions(samples))
}

/// Per-fragment capture with coverage masks: each (pixel, triangle) covering any sample once,
/// nearest first by its centre depth, with its mask.
#[derive(Clone, Debug)]
pub struct CoverageLists {
    pub samples: u32,
    /// Depth and attributes at the pixel centre.
    pub lists: FragmentLists,
    /// Parallel to `lists.frags`: bit s set where the triangle covers sample s.
    pub masks: Vec<u32>,
}

/// The coverage-mask view of `samples` standard positions (attributes at the pixel centre).
pub fn coverage_lists(scene: &Scene, width: u32, height: u32, samples: u32) -> CoverageLists {
    let (lists, masks) = rasterize_with(
        scene,
        width,
        height,
        Sampling {
            coverage: standard_positions(samples),
            attributes: CENTRE.attributes,
            depth: None,
        },
    );
    CoverageLists {
        samples,
        lists,
        masks,
    }
}

impl CoverageLists {
    /// The fragments of pixel `p` that cover sample `s`, nearest first.
    pub fn at_sample(&self, p: usize, s: u32) -> impl Iterator<Item = &RefFragment> {
        let (a, b) = (
            self.lists.offsets[p] as usize,
            self.lists.offsets[p + 1] as usize,
        );
        self.lists.frags[a..b]
            .iter()
            .zip(&self.masks[a..b])
            .filter(move |(_, &m)| m & (1 << s) != 0)
            .map(|(f, _)| f)
    }

    /// The lists of sample `s` alone (so any per-pixel rule, e.g. an effect, applies per sample).
    pub fn sample(&self, s: u32) -> FragmentLists {
        let mut offsets = Vec::with_capacity(self.lists.offsets.len());
        let mut frags = Vec::new();
        offsets.push(0);
        for p in 0..self.lists.pixels() {
            frags.extend(self.at_sample(p, s).copied());
            offsets.push(frags.len() as u32);
        }
        FragmentLists {
            width: self.lists.width,
            height: self.lists.height,
            reversed_z: self.lists.reversed_z,
            offsets,
            frags,
        }
    }

    /// Transparency of each pixel: the mean over samples of the composite of the fragments
    /// covering the sample (at most the `k` nearest of them).
    pub fn composite_first(&self, k: usize) -> Vec<[f64; 4]> {
        (0..self.lists.pixels())
            .map(|p| {
                let per: Vec<[f64; 4]> = (0..self.samples)
                    .map(|s| composite(self.at_sample(p, s).take(k)))
                    .collect();
                mean4(&per)
            })
            .collect()
    }
}

fn mean4(v: &[[f64; 4]]) -> [f64; 4] {
    let mut m = [0.0; 4];
    for x in v {
        for c in 0..4 {
            m[c] += x[c];
        }
    }
    m.map(|c| c / v.len().max(1) as f64)
}

/// The mean of per-sample images (all of one size): the resolve of a multisampled image.
pub fn resolve(per_sample: &[Vec<[f64; 4]>]) -> Vec<[f64; 4]> {
    let n = per_sample.first().map_or(0, |v| v.len());
    let mut out = vec![[0.0; 4]; n];
    for img in per_sample {
        assert_eq!(img.len(), n, "per-sample images differ in size");
        for (o, x) in out.iter_mut().zip(img) {
            for c in 0..4 {
                o[c] += x[c];
            }
        }
    }
    let s = per_sample.len().max(1) as f64;
    for o in &mut out {
        for c in o.iter_mut() {
            *c /= s;
        }
    }
    out
}

/// 2×2 box filter of `images` images of (2w)×(2h) pixels, one after another, into w×h each.
pub fn box_filter_2x2(img: &[[f64; 4]], width: u32, height: u32) -> Vec<[f64; 4]> {
    let (w, h) = (width as usize, height as usize);
    let big = 4 * w * h;
    assert!(
        big > 0 && img.len().is_multiple_of(big),
        "{} pixels is not a whole number of {}×{} images",
        img.len(),
        2 * w,
        2 * h
    );
    let mut out = Vec::with_capacity(img.len() / 4);
    for image in img.chunks(big) {
        for y in 0..h {
            for x in 0..w {
                let at = |dx: usize, dy: usize| image[(2 * y + dy) * 2 * w + 2 * x + dx];
                out.push(mean4(&[at(0, 0), at(1, 0), at(0, 1), at(1, 1)]));
            }
        }
    }
    out
}
