//! Judging a capture against the exact reference: a pure function of the capture, the
//! reference's fragment lists, the scene and the effect (no GPU), so every rule here is tested
//! on hand-made captures.
//!
//! - **Ground truth is the whole composite.** `rmse`, `psnr_db`, `max_abs_err`,
//!   `bad_pixel_frac`, `flip_*` compare the image with the same effect over *every* fragment.
//! - **Fidelity to the method's own definition** is separate (`*_vs_k`): the same effect over
//!   the k nearest (or first) fragments for a method that keeps k, or the method's CPU twin
//!   (`Capture.definition`), e.g. k nearest plus a blended tail.
//! - **`exact`** is a fact about fragments: no fragment lost or merged (no loss flag, no
//!   overflow, collision or hazard) and every pixel within the f32 bound of its arithmetic of
//!   the ground truth ([`exact_bounds`], derived there; the largest is `exact_bound`). It
//!   implies `matches_truth`.
//! - **`matches_truth`** is the weaker label: every pixel within `bad_pixel_tol` of the ground
//!   truth and nothing non-finite (a capture that dropped fragments can still match).
//! - **`depth_ties`**: fragments within the method's depth precision of each other have no
//!   defined order, so the truth is ambiguous at their pixels. An image off the truth there by
//!   what another order of them makes ([`tie_order_explains`]) is neither exact nor
//!   `image_differs`: it is flagged `depth_ties`, its pixels counted in `depth_tie_pixels`. An
//!   error no order makes (a fragment's attributes off) is not a tie, however near its depths.
//! - **Flags** name each known failure (`record::Flag`); counts behind them are columns.

use std::sync::{Arc, Mutex};

use scenarios::Scene;

use crate::effects::{Effect, EffectConfig};
use crate::method::{Capture, Expected};
use bench_core::record::{cols, Flag, FlagSet, Row};
use mfx_reference::metrics::{image_error, layer_count_accuracy, ImageError, BAD_PIXEL_TOL};
use mfx_reference::{AaMode, FragmentLists, RefFragment};

/// What the judge needs besides the capture and the reference.
#[derive(Clone, Copy, Debug)]
pub struct Context<'a> {
    pub scene: &'a Scene,
    pub effect: &'a EffectConfig,
    /// The method claims to capture every fragment (within capacity).
    pub exact: bool,
    /// Compute FLIP (a perceptual error, ~0.1 s per 1024² image on 16 cores).
    pub flip: bool,
    /// Reference images already composited for this scene's fragment lists (a group's rows
    /// share them); None: computed for this call only.
    pub truths: Option<&'a TruthCache>,
}

/// Reference images of one set of fragment lists by (effect, expected): the default suite
/// judged every row against a truth composited anew from the same lists (up to ~20 rows a
/// group at 1024²).
#[derive(Debug, Default)]
pub struct TruthCache(Mutex<Vec<(EffectConfig, Expected, Image)>>);

/// A reference image, shared.
pub type Image = Arc<Vec<[f64; 4]>>;

impl TruthCache {
    /// The cached image of (`effect`, `expected`), computed by `make` on first use.
    pub fn get(
        &self,
        effect: &EffectConfig,
        expected: Expected,
        make: impl FnOnce() -> Vec<[f64; 4]>,
    ) -> Arc<Vec<[f64; 4]>> {
        if let Some((_, _, img)) = self
            .0
            .lock()
            .unwrap()
            .iter()
            .find(|(e, x, _)| e == effect && *x == expected)
        {
            return img.clone();
        }
        let img = Arc::new(make());
        self.0
            .lock()
            .unwrap()
            .push((*effect, expected, img.clone()));
        img
    }

    /// Images held.
    pub fn len(&self) -> usize {
        self.0.lock().unwrap().len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// `cx`'s reference image of `expected`: from its cache when it has one.
fn reference_image(
    cx: &Context<'_>,
    lists: &FragmentLists,
    expected: Expected,
) -> Arc<Vec<[f64; 4]>> {
    let make = || cx.effect.reference(cx.scene, lists, expected);
    match cx.truths {
        Some(c) => c.get(cx.effect, expected, make),
        None => Arc::new(make()),
    }
}

/// FLIP of a row, with the 8-bit images it was computed from (for the worst-points gallery).
pub type Flip = bench_core::record::FlipImages;

/// The verdict on one capture.
#[derive(Clone, Debug, Default)]
pub struct Judgement {
    /// vs the ground truth (None without an image).
    pub truth: Option<ImageError>,
    /// vs the method's own definition (k-truncated composite or its CPU twin), when it keeps
    /// less than everything.
    pub vs_k: Option<ImageError>,
    pub matches_truth: Option<bool>,
    /// Samples per output pixel of an antialiased capture (`aa_samples`).
    pub aa_samples: Option<u32>,
    /// What the sample-position probe found (`sample_positions`).
    pub sample_positions: Option<String>,
    pub flip: Option<Flip>,
    pub overflow_rate: f64,
    pub layer_count_accuracy: Option<f64>,
    pub layers_captured_max: Option<u32>,
    /// Fragments within capacity the method did not capture, at depth ties / elsewhere.
    pub lost_coplanar: u64,
    pub lost_precision: u64,
    /// Exact methods: fragments missing / extra vs the reference, summed over pixels.
    pub fragments_missing: Option<u64>,
    pub fragments_extra: Option<u64>,
    pub collision_rate: Option<f64>,
    pub hazard_rate: Option<f64>,
    /// `exact`: no fragment lost or merged and the image within `exact_bound` (None without an
    /// image).
    pub exact: Option<bool>,
    /// The largest per-pixel bound `exact` was judged with ([`exact_bounds`]).
    pub exact_bound: Option<f64>,
    /// Pixels off the truth beyond their arithmetic bound by what another order of their
    /// near-equal-depth fragments makes ([`tie_order_explains`]; flag `depth_ties`; None without
    /// an image or for a method that does not claim every fragment).
    pub depth_tie_pixels: Option<u64>,
    /// Known flags and the method's own words (kept, never dropped); only added to.
    pub flags: FlagSet,
    pub notes: Vec<String>,
}

impl Judgement {
    fn flag(&mut self, f: Flag) {
        self.flags.add(f);
    }

    /// Writes the judged columns and flags into `row`.
    pub fn write(&self, row: &mut Row) {
        if let Some(e) = &self.truth {
            row.set_f(cols::RMSE, e.rmse)
                .set_f(cols::PSNR_DB, e.psnr_db)
                .set_f(cols::MAX_ABS_ERR, e.max_abs)
                .set_f(cols::BAD_PIXEL_FRAC, e.bad_pixel_frac)
                .set_f(cols::BAD_PIXEL_TOL, BAD_PIXEL_TOL)
                .set(cols::NON_FINITE, e.non_finite);
        }
        if let Some(e) = &self.vs_k {
            row.set_f(cols::RMSE_VS_K, e.rmse)
                .set_f(cols::PSNR_DB_VS_K, e.psnr_db)
                .set_f(cols::MAX_ABS_ERR_VS_K, e.max_abs)
                .set_f(cols::BAD_PIXEL_FRAC_VS_K, e.bad_pixel_frac);
        }
        row.set_opt(cols::MATCHES_TRUTH, self.matches_truth);
        row.set_opt(cols::EXACT, self.exact);
        if let Some(b) = self.exact_bound {
            row.set_f(cols::EXACT_BOUND, b);
        }
        row.set_opt(cols::DEPTH_TIE_PIXELS, self.depth_tie_pixels);
        row.set_opt(cols::AA_SAMPLES, self.aa_samples);
        if let Some(s) = &self.sample_positions {
            row.set(cols::SAMPLE_POSITIONS, s.as_str());
        }
        if let Some(f) = &self.flip {
            row.set_f(cols::FLIP_MEAN, f.result.mean)
                .set_f(cols::FLIP_P99, f.result.p99);
            row.flip = Some(Box::new(f.clone()));
        }
        row.set_f(cols::OVERFLOW_RATE, self.overflow_rate);
        if let Some(a) = self.layer_count_accuracy {
            row.set_f(cols::LAYER_COUNT_ACCURACY, a);
        }
        row.set_opt(cols::LAYERS_CAPTURED_MAX, self.layers_captured_max);
        if self.layer_count_accuracy.is_some() {
            row.set(
                cols::LOST_FRAGMENTS,
                self.lost_coplanar + self.lost_precision,
            );
        }
        row.set_opt(cols::FRAGMENTS_MISSING, self.fragments_missing)
            .set_opt(cols::FRAGMENTS_EXTRA, self.fragments_extra);
        if let Some(c) = self.collision_rate {
            row.set_f(cols::COLLISION_RATE, c);
        }
        if let Some(h) = self.hazard_rate {
            row.set_f(cols::HAZARD_RATE, h);
        }
        row.add_flags(&self.flags);
        for n in &self.notes {
            row.add_note(n);
        }
    }
}

/// Why a capture cannot be compared with its reference: its row is `failed` with this text.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum JudgeError {
    #[error("counts cover {counts} pixels, the reference {reference}")]
    CountsSize { counts: usize, reference: usize },
    #[error("image has {image} pixels, the {effect} ground truth {truth}")]
    TruthSize {
        image: usize,
        effect: String,
        truth: usize,
    },
    #[error("image has {image} pixels, the method's own definition {own}")]
    DefinitionSize { image: usize, own: usize },
    /// A study that compares images (the views study) got a capture without one.
    #[error("the method made no image")]
    NoImage,
}

/// Judges `cap` against `lists`. `Err` when the image cannot be compared (wrong size).
pub fn judge(
    cap: &Capture,
    lists: &FragmentLists,
    cx: Context<'_>,
) -> Result<Judgement, JudgeError> {
    let mut j = Judgement::default();
    j.flags.add_all(&cap.flag);
    // An antialiased capture is judged against the multisampled truth of its mode; its depth
    // complexity is the most fragments at one sample of a pixel (what a FirstK(k) overflows on).
    let aa = crate::aa::reference_for(cap, cx.scene, lists, cx.effect);
    if let Some(a) = &aa {
        j.aa_samples = Some(match a.mode {
            AaMode::Msaa(n) => n,
            AaMode::Ssaa2x2 => 4,
            AaMode::None => 1,
        });
        j.sample_positions = cap.sample_positions.clone();
    }
    let dc = match &aa {
        Some(a) => a.depth_complexity.clone(),
        None => lists.depth_complexity(),
    };
    let px = dc.len().max(1);
    let k = match cap.expected {
        Expected::All => u32::MAX,
        Expected::FirstK(k) => k,
    };
    // Beyond a FirstK capacity, or as the method counted it (pools, unpeeled layers).
    let overflow = dc
        .iter()
        .filter(|&&d| d > k)
        .count()
        .max(cap.overflow_pixels.unwrap_or(0) as usize);
    j.overflow_rate = overflow as f64 / px as f64;
    if overflow > 0 {
        j.flag(Flag::Overflow);
    }

    // Per-pixel counts are single-sample by contract (an AA capture leaves them `None`).
    if let (Some(counts), None) = (&cap.counts, &aa) {
        if counts.len() != dc.len() {
            return Err(JudgeError::CountsSize {
                counts: counts.len(),
                reference: dc.len(),
            });
        }
        // Fragments the method should have captured (within its k) but did not: at a pixel
        // whose f64 reference has exact depth ties this is strict peeling's coplanar loss;
        // elsewhere distinct layers merged in the method's own depth precision.
        let (mut missing, mut extra) = (0u64, 0u64);
        for (p, (&d, &c)) in dc.iter().zip(counts).enumerate() {
            let want = d.min(k);
            let lost = want.saturating_sub(c) as u64;
            if lost > 0 {
                if lists.pixel(p).windows(2).any(|w| w[0].depth == w[1].depth) {
                    j.lost_coplanar += lost;
                } else {
                    j.lost_precision += lost;
                }
            }
            missing += d.saturating_sub(c) as u64;
            extra += c.saturating_sub(d) as u64;
        }
        // A bucket method's losses are its collisions (flagged `collision` by the method, counted
        // in `collision_rate`): coplanar or precision loss is flagged only beyond them, so one
        // lost fragment is never two failures.
        let collided = cap.collision_fragments.unwrap_or(0);
        if j.lost_coplanar + j.lost_precision > collided {
            if j.lost_coplanar > 0 {
                j.flag(Flag::LostCoplanar);
            } else if j.lost_precision > 0 && overflow == 0 {
                j.flag(Flag::Precision);
            }
        }
        // An exact method is held to the whole fragment set when it keeps everything, or keeps k
        // and no pixel has more (peeling with max_layers ≥ the depth complexity).
        let all_within = cap.expected == Expected::All || dc.iter().all(|&d| d <= k);
        if cx.exact && all_within {
            j.fragments_missing = Some(missing);
            j.fragments_extra = Some(extra);
            // Missing fragments with an overflow are the overflow's; extra ones never are. A
            // method that keeps k may lose coplanar ties by its definition (strict peeling): those
            // are flagged lost_coplanar, not as a different set.
            let unexplained = match cap.expected {
                Expected::All => missing,
                Expected::FirstK(_) => missing.saturating_sub(j.lost_coplanar),
            };
            if extra > 0 || (unexplained > 0 && overflow == 0) {
                j.flag(Flag::FragmentsDiffer);
                j.notes.push(format!(
                    "fragment set differs from the reference: {missing} missing, {extra} extra"
                ));
            }
        }
        let expected: Vec<u32> = dc.iter().map(|&d| d.min(k)).collect();
        j.layer_count_accuracy = Some(layer_count_accuracy(&expected, counts));
        j.layers_captured_max = Some(counts.iter().max().copied().unwrap_or(0));
    }

    if let Some(img) = &cap.image {
        let truth = match &aa {
            Some(a) => Arc::new(a.truth.clone()),
            None => reference_image(&cx, lists, Expected::All),
        };
        if truth.len() != img.len() {
            return Err(JudgeError::TruthSize {
                image: img.len(),
                effect: cx.effect.effect.name().to_string(),
                truth: truth.len(),
            });
        }
        let e = image_error(&truth, img, BAD_PIXEL_TOL);
        j.matches_truth = Some(e.bad_pixel_frac == 0.0 && e.non_finite == 0);
        if e.non_finite > 0 {
            j.flag(Flag::Precision);
        }
        j.truth = Some(e);
        let own = match (&cap.definition, cap.expected) {
            _ if aa.is_some() => aa.as_ref().and_then(|a| a.own.clone()),
            (Some(d), _) => Some(d.clone()),
            (None, Expected::FirstK(k)) => {
                Some(reference_image(&cx, lists, Expected::FirstK(k)).to_vec())
            }
            (None, Expected::All) => None,
        };
        if let Some(own) = &own {
            if own.len() != img.len() {
                return Err(JudgeError::DefinitionSize {
                    image: img.len(),
                    own: own.len(),
                });
            }
            j.vs_k = Some(image_error(own, img, BAD_PIXEL_TOL));
        }
        let own_img = own;
        // Per pixel: the f32 bound of the arithmetic that made it, and what another order of its
        // near-equal-depth fragments can add (see exact_bounds).
        let bounds = exact_bounds(&dc, (aa.is_none() && lists.pixels() == px).then_some(lists));
        let bound_of = |i: usize| bounds[i % px];
        j.exact_bound = Some(bounds.iter().map(|b| b.arith).fold(0.0, f64::max));
        // Pixels beyond their capacity (FirstK): their difference is the overflow's. A count of
        // overflowing pixels the method made itself (a pool) does not say which pixels: then
        // every pixel may be one.
        let counted_elsewhere =
            cap.overflow_pixels.unwrap_or(0) as usize > dc.iter().filter(|&&d| d > k).count();
        let over = |i: usize| counted_elsewhere || dc[i % px] > k;
        // An image off its own definition (k-truncated composite, CPU twin, or for a method
        // keeping everything the truth) at a pixel within capacity, by more than both
        // bad_pixel_tol and the pixel's f32 bound, that no flag explains. The same rule for every
        // method held to a definition, per pixel: it once applied only to methods claiming
        // exactness and only when no pixel of the image overflowed, so on lavapipe's grass the
        // exact methods were `image_differs` at one pixel and kbuffer_rmw (which overflowed
        // elsewhere) with the identical image was not.
        let explained = j.flags.iter().any(|f| {
            matches!(
                f,
                Flag::LostCoplanar
                    | Flag::Precision
                    | Flag::FragmentsDiffer
                    | Flag::Hazard
                    | Flag::Collision
            )
        });
        let definition: Option<&[[f64; 4]]> = match &own_img {
            Some(o) => Some(o.as_slice()),
            None if cx.exact => Some(truth.as_slice()),
            None => None,
        };
        // Whether another order of pixel i's near-equal-depth fragments explains an error `e`
        // of the image against the truth beyond its arithmetic (`tie_order_explains`).
        let lists_per_pixel = aa.is_none() && lists.pixels() == px;
        let order_explains = |i: usize, e: f64| {
            let b = bound_of(i);
            e <= b.with_order()
                && match cx.effect.effect {
                    Effect::Transparency if lists_per_pixel && i < px => {
                        tie_order_explains(lists.pixel(i), img[i].map(f64::from), truth[i], b.arith)
                    }
                    // Thickness and Fresnel are sums and products: no order changes them.
                    Effect::Translucency | Effect::Fresnel => false,
                    // A volume's or an isosurface's error beyond its arithmetic comes from its
                    // segments' attributes (a raster method interpolates unsnapped vertices),
                    // not from an order of ties: never excused as `depth_ties`.
                    Effect::Volume | Effect::Isosurface => false,
                    // CSG and depth-of-field pick fragments by order: held to the order bound.
                    _ => true,
                }
        };
        let held_to_truth = own_img.is_none();
        if let (Some(def), false) = (definition, explained) {
            let off = img
                .iter()
                .zip(def)
                .enumerate()
                .filter(|&(i, (g, w))| {
                    let e = pixel_err(g, w);
                    let excused = if held_to_truth {
                        order_explains(i, e)
                    } else {
                        e <= bound_of(i).with_order()
                    };
                    !over(i) && e > BAD_PIXEL_TOL.max(bound_of(i).arith) && !excused
                })
                .count();
            if off > 0 {
                j.flag(Flag::ImageDiffers);
                j.notes.push(format!(
                    "image differs from its definition at {off} pixels ({:.3} %) beyond max(bad_pixel_tol, the f32 bound)",
                    100.0 * off as f64 / img.len() as f64
                ));
            }
        }
        // Pixels off the truth beyond their arithmetic but within another order of their ties:
        // judged for methods that claim every fragment, within capacity (an approximation's or
        // an overflow's error there is not a tie order).
        let errs: Vec<f64> = img
            .iter()
            .zip(truth.iter())
            .map(|(g, w)| pixel_err(g, w))
            .collect();
        if cx.exact {
            let ties = errs
                .iter()
                .enumerate()
                .filter(|&(i, &e)| !over(i) && e > bound_of(i).arith && order_explains(i, e))
                .count() as u64;
            j.depth_tie_pixels = Some(ties);
            if ties > 0 {
                j.flag(Flag::DepthTies);
            }
        }
        // Exact: nothing lost or merged, every pixel within its f32 bound of the truth (no tie
        // order allowed: the truth has one order), and so within bad_pixel_tol (a bound above
        // it, at ~1000 layers, does not make a pixel beyond the tolerance exact).
        let lost = j.flags.has_loss()
            || overflow > 0
            || cap.collision_fragments.is_some_and(|c| c > 0)
            || cap.hazard_pixels.is_some_and(|h| h > 0)
            || j.truth.as_ref().is_some_and(|e| e.non_finite > 0);
        j.exact = Some(
            !lost
                && j.matches_truth == Some(true)
                && errs
                    .iter()
                    .enumerate()
                    .all(|(i, &e)| e <= bound_of(i).arith),
        );
        // Not exact with nothing lost and no flag: say why in the notes, so the row does not
        // read as unexplained (on the H200, translucency and Fresnel by methods holding every
        // fragment: the bound is the transparency composite's, not the effect's own arithmetic).
        if j.exact == Some(false) && !lost && j.flags.is_empty() {
            let beyond = errs
                .iter()
                .enumerate()
                .filter(|&(i, &e)| !over(i) && e > bound_of(i).arith)
                .count();
            if beyond > 0 {
                j.notes.push(format!(
                    "not exact: {beyond} pixels beyond the f32 bound of compositing (derived for transparency; {} is held to it), within bad_pixel_tol",
                    cx.effect.effect.name()
                ));
            }
        }
        if cx.flip {
            j.flip = Some(flip(&truth, img, lists.width, lists.height));
        }
    }
    if let Some(c) = cap.collision_fragments {
        j.collision_rate = Some(c as f64 / lists.total_fragments().max(1) as f64);
    }
    if let Some(h) = cap.hazard_pixels {
        j.hazard_rate = Some(h as f64 / px as f64);
    }
    if !cap.notes.is_empty() {
        j.notes.insert(0, cap.notes.clone());
    }
    Ok(j)
}

/// Unit roundoff of f32 (round to nearest): 2⁻²⁴.
const F32_U: f64 = 1.0 / 16_777_216.0;
/// f32 roundings a pixel's compositing may accumulate per fragment, and once, in units of
/// [`F32_U`] (derivation at [`exact_bounds`]).
const ULPS_PER_LAYER: f64 = 32.0;
const ULPS_FIXED: f64 = 4.0;

/// A pixel's max-abs bounds: its f32 arithmetic, and what another order of its near-equal-depth
/// fragments can add.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelBound {
    /// Within this, an image that composited every fragment in the truth's order, in f32, equals
    /// the f64 truth: what `exact` is judged with.
    pub arith: f64,
    /// What compositing runs of fragments within `store::DEPTH_TOL` in another order can add
    /// (0 without ties or without the lists): a difference up to `arith + order` may be
    /// `depth_ties`, where an order makes it ([`tie_order_explains`]).
    pub order: f64,
}

impl PixelBound {
    pub fn with_order(self) -> f64 {
        self.arith + self.order
    }
}

/// The max-abs bounds per pixel within which an image that composited every fragment, in f32,
/// equals the f64 truth (`arith`, what `exact` is judged with), and within which it is one of
/// the truths another order of near-equal-depth fragments makes (`arith + order`).
///
/// **Arithmetic.** Every judged image is f32 (storage buffers or `Rgba32Float` targets: no
/// 8-bit quantisation; vertex colours are f32 in both the GPU scene and the reference). The
/// fold composites front to back, `C += T·a·c; T *= 1 − a`: ≤ 3 roundings for the colour term
/// and 2 for the transmittance per step, so after i steps |ΔT_i| ≤ 2i·u·T_i and term i is off by
/// ≤ (2i + 3)·u·T_i·a_i·c_i; as Σ T_i·a_i ≤ 1 and c ≤ 1 the sum is off by ≤ (2n + 3)·u. The GPU
/// interpolates a and c in f32 (≤ 8 u each, relative, at the pixel centre): another ≤ 16·u·n
/// through the terms and 8·u·n through T. In all ≤ (26·n + 3)·u, rounded up to (32·n + 4)·u
/// (16 layers: 3.1e-5; the k-buffers' tests measure under 2e-5 there).
///
/// **Order at the method's depth precision.** A method orders fragments by its own f32 depth,
/// which can sit up to `store::DEPTH_TOL` from the f64 one (grazing triangles), so a run of
/// fragments each within that of the next may be composited in any order. The run's total
/// opacity 1 − Π(1 − a_i), and so everything behind it, does not depend on the order; its colour
/// is that opacity times a convex combination of its colours. Any order is therefore within
/// T·(1 − Π(1 − a_i))·(max c − min c) of the truth, T ≤ 1 in front of it; each such run adds that
/// to the `order` bound (with `lists`; derived for the transparency fold, the other effects are
/// held to the same bound). It is not part of `exact`'s bound: the H200's compute A-buffer on
/// grass was 0.009–0.04 off the truth within an order bound of 0.15–0.22, "exact" yet beyond
/// `bad_pixel_tol`; such a row is `depth_ties`. The bound only admits a pixel: it is a tie where
/// an order of its runs makes its error ([`tie_order_explains`]), since a fragment's colour off
/// by less than its run's spread is within it too (issue 41: on the ogres most pixels it admitted
/// were attribute errors). The order bound is why the compute A-buffer's
/// deep H200 scenes, `image_differs` once at RMSE 2e-5–1.2e-4 with identical fragment sets, are
/// not where the difference is such an order; a difference beyond it (0.047 at 2 pixels of the
/// 16-bunny stack) is not arithmetic but another fragment: one triangle's where the reference
/// has its neighbour's (f32 vertex snapping at a shared edge keeps the counts equal), and stays
/// `image_differs`.
pub fn exact_bounds(dc: &[u32], lists: Option<&FragmentLists>) -> Vec<PixelBound> {
    let tol = crate::methods::shared::store::DEPTH_TOL;
    dc.iter()
        .enumerate()
        .map(|(p, &n)| {
            let arith = (ULPS_PER_LAYER * n as f64 + ULPS_FIXED) * F32_U;
            let orders: f64 = lists.map_or(0.0, |l| {
                let frags = l.pixel(p);
                let mut sum = 0.0;
                let mut i = 0;
                while i < frags.len() {
                    let mut e = i + 1;
                    while e < frags.len() && (frags[e].depth - frags[e - 1].depth).abs() <= tol {
                        e += 1;
                    }
                    let run = &frags[i..e];
                    if run.len() > 1 {
                        let opacity = 1.0 - run.iter().map(|f| 1.0 - f.color[3]).product::<f64>();
                        let spread = (0..3)
                            .map(|c| {
                                let (lo, hi) =
                                    run.iter().fold((f64::MAX, f64::MIN), |(lo, hi), f| {
                                        (lo.min(f.color[c]), hi.max(f.color[c]))
                                    });
                                hi - lo
                            })
                            .fold(0.0, f64::max);
                        sum += opacity * spread;
                    }
                    i = e;
                }
                sum
            });
            PixelBound {
                arith,
                order: orders,
            }
        })
        .collect()
}

/// Orders of a pixel's near-equal-depth runs searched one by one in [`tie_order_explains`]
/// (7!: one run of seven, or several shorter ones); beyond, each channel is held to the range
/// the orders span.
const TIE_ORDERS_SEARCHED: u64 = 5040;

/// Whether compositing `frags` (a pixel's fragments in the truth's order) with its runs of
/// near-equal-depth fragments (each within `store::DEPTH_TOL` of the next, as [`exact_bounds`]
/// finds them) in some other order gives `got` within `arith` on every channel, where `truth`
/// is their composite in the truth's order (transparency's under operator).
///
/// A run's opacity, and so everything behind it and the alpha channel, is the same in any
/// order; only its colour moves, to T·Σ aᵢcᵢΠⱼ₍ᵦₑfₒᵣₑ ᵢ₎(1 − aⱼ) for the order taken (T: the
/// transmittance in front of it). The error of a tie order is so a sum of one such move per run.
/// Where the runs have at most [`TIE_ORDERS_SEARCHED`] orders together every combination is
/// tried; beyond, each colour channel must lie within the range the orders span (a run's
/// channel is largest with its colours in decreasing order and smallest in increasing: swapping
/// neighbours i, j changes it by aᵢaⱼ(cᵢ − cⱼ) times what is in front), a necessary condition.
/// An error no order makes — a fragment's colour off, its attributes interpolated otherwise than
/// the reference's — is not a tie, whatever the order bound admits.
pub fn tie_order_explains(
    frags: &[RefFragment],
    got: [f64; 4],
    truth: [f64; 4],
    arith: f64,
) -> bool {
    if (got[3] - truth[3]).abs() > arith {
        return false;
    }
    let want = [0, 1, 2].map(|c| got[c] - truth[c]);
    // Each run of two or more: the colour moves its orders make, or (too many) their ranges.
    let tol = crate::methods::shared::store::DEPTH_TOL;
    let mut runs: Vec<(f64, &[RefFragment])> = Vec::new();
    let (mut t, mut i) = (1.0f64, 0);
    while i < frags.len() {
        let mut e = i + 1;
        while e < frags.len() && (frags[e].depth - frags[e - 1].depth).abs() <= tol {
            e += 1;
        }
        if e - i > 1 {
            runs.push((t, &frags[i..e]));
        }
        t *= frags[i..e]
            .iter()
            .map(|f| 1.0 - f.color[3])
            .product::<f64>();
        i = e;
    }
    let orders = runs.iter().fold(1u64, |n, (_, r)| {
        (1..=r.len() as u64).fold(n, |n, k| n.saturating_mul(k))
    });
    let colour = |t: f64, run: &mut dyn Iterator<Item = &RefFragment>| {
        let (mut c, mut tr) = ([0.0f64; 3], t);
        for f in run {
            for (ch, v) in c.iter_mut().enumerate() {
                *v += tr * f.color[3] * f.color[ch];
            }
            tr *= 1.0 - f.color[3];
        }
        c
    };
    let within = |d: [f64; 3]| (0..3).all(|c| (want[c] - d[c]).abs() <= arith);
    if orders <= TIE_ORDERS_SEARCHED {
        let mut sums = vec![[0.0f64; 3]];
        for (t, run) in &runs {
            let base = colour(*t, &mut run.iter());
            let mut moves = Vec::new();
            for_each_order(run.len(), &mut |perm| {
                let c = colour(*t, &mut perm.iter().map(|&k| &run[k]));
                moves.push([0, 1, 2].map(|ch| c[ch] - base[ch]));
            });
            sums = sums
                .iter()
                .flat_map(|s| moves.iter().map(move |m| [0, 1, 2].map(|c| s[c] + m[c])))
                .collect();
        }
        return sums.into_iter().any(within);
    }
    (0..3).all(|ch| {
        let (mut lo, mut hi) = (0.0, 0.0);
        for (t, run) in &runs {
            let base = colour(*t, &mut run.iter())[ch];
            let mut sorted: Vec<&RefFragment> = run.iter().collect();
            sorted.sort_by(|a, b| b.color[ch].total_cmp(&a.color[ch]));
            hi += colour(*t, &mut sorted.iter().copied())[ch] - base;
            lo += colour(*t, &mut sorted.iter().rev().copied())[ch] - base;
        }
        want[ch] >= lo - arith && want[ch] <= hi + arith
    })
}

/// Calls `f` with every permutation of `0..n` (Heap's algorithm).
fn for_each_order(n: usize, f: &mut dyn FnMut(&[usize])) {
    let mut a: Vec<usize> = (0..n).collect();
    let mut c = vec![0usize; n];
    f(&a);
    let mut i = 0;
    while i < n {
        if c[i] < i {
            a.swap(if i % 2 == 0 { 0 } else { c[i] }, i);
            f(&a);
            c[i] += 1;
            i = 0;
        } else {
            c[i] = 0;
            i += 1;
        }
    }
}

/// Largest channel error of a pixel (∞ when a channel is not finite).
fn pixel_err(g: &[f32; 4], w: &[f64; 4]) -> f64 {
    (0..4)
        .map(|c| {
            let v = g[c] as f64;
            if v.is_finite() {
                (v - w[c]).abs()
            } else {
                f64::INFINITY
            }
        })
        .fold(0.0, f64::max)
}

/// FLIP of an image against the truth, both composited over white as the PNGs show them; an
/// effect with several images (dof) is judged as the images stacked vertically.
fn flip(truth: &[[f64; 4]], img: &[[f32; 4]], w: u32, h: u32) -> Flip {
    let stacked = (img.len() / (w * h).max(1) as usize).max(1) as u32;
    let truth32: Vec<[f32; 4]> = truth.iter().map(|p| p.map(|c| c as f32)).collect();
    let white = [1.0f32; 3];
    let truth_rgb8 = mfx_flip::composite_srgb8(&truth32, white);
    let method_rgb8 = mfx_flip::composite_srgb8(img, white);
    let result = mfx_flip::flip_ldr(&truth_rgb8, &method_rgb8, w, h * stacked, mfx_flip::PPD);
    Flip {
        result,
        method_rgb8,
        truth_rgb8,
        width: w,
        height: h * stacked,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scenarios::{Camera, Mesh, Params, SceneSpec};

    /// `dc[p]` fragments per pixel at depths 0.1, 0.2, … (ties where `tie` says), colour 0.5
    /// with alpha 0.5.
    fn lists(dc: &[u32], tie: bool) -> FragmentLists {
        let mut offsets = vec![0u32];
        let mut frags = Vec::new();
        for &d in dc {
            for i in 0..d {
                let z = if tie { 0.5 } else { 0.1 * (i + 1) as f64 };
                frags.push(RefFragment {
                    depth: z,
                    view_z: z * 10.0,
                    color: [0.2 + 0.1 * i as f64, 0.5, 0.5, 0.5],
                    normal: [0.0, 0.0, 1.0],
                    object_id: i,
                    front_facing: true,
                    prim: i,
                    depth_slope: 0.0,
                });
            }
            offsets.push(frags.len() as u32);
        }
        FragmentLists {
            width: dc.len() as u32,
            height: 1,
            reversed_z: false,
            offsets,
            frags,
        }
    }

    fn scene() -> Scene {
        let cam = Camera::look_at(
            glam::DVec3::new(0.0, 0.0, 5.0),
            glam::DVec3::ZERO,
            45.0,
            0.1,
            100.0,
        );
        Scene::new(SceneSpec::new("test", Params::new()), Mesh::default(), cam)
    }

    fn cap_with(img: Vec<[f64; 4]>, counts: Vec<u32>, expected: Expected) -> Capture {
        let mut c = Capture::empty();
        c.image = Some(img.iter().map(|p| p.map(|v| v as f32)).collect());
        c.counts = Some(counts);
        c.expected = expected;
        c
    }

    fn run(cap: &Capture, l: &FragmentLists, exact: bool) -> Judgement {
        let s = scene();
        let e = EffectConfig::default();
        judge(
            cap,
            l,
            Context {
                scene: &s,
                effect: &e,
                exact,
                flip: false,
                truths: None,
            },
        )
        .unwrap()
    }

    #[test]
    fn a_truncated_image_is_wrong_vs_the_truth_and_right_vs_its_own_definition() {
        // 4 layers per pixel, a method keeping the 2 nearest and compositing them exactly.
        let l = lists(&[4, 4, 4], false);
        let cap = cap_with(l.composite_first(2), vec![2, 2, 2], Expected::FirstK(2));
        let j = run(&cap, &l, true);
        assert!(j.truth.unwrap().rmse > 0.05, "{:?}", j.truth);
        assert!(j.vs_k.unwrap().rmse < 1e-7, "{:?}", j.vs_k);
        assert_eq!(j.matches_truth, Some(false));
        assert!(j.flags.contains(Flag::Overflow));
        assert_eq!(j.overflow_rate, 1.0);
        // Counts equal min(dc, k): no fragment lost within capacity.
        assert_eq!(j.layer_count_accuracy, Some(1.0));
        assert_eq!(j.lost_coplanar + j.lost_precision, 0);
    }

    #[test]
    fn a_collision_is_flagged_once_not_also_as_precision_or_coplanar_loss() {
        // 4 layers per pixel; a bucket method merged one fragment of each pixel into another.
        for tie in [false, true] {
            let l = lists(&[4, 4, 4], tie);
            let mut cap = cap_with(l.composite(), vec![3, 3, 3], Expected::All);
            cap.collision_fragments = Some(3);
            let j = run(&cap, &l, false);
            assert_eq!(j.lost_coplanar + j.lost_precision, 3, "tie {tie}");
            assert!(
                !j.flags.contains(Flag::Precision) && !j.flags.contains(Flag::LostCoplanar),
                "tie {tie}: {:?}",
                j.flags
            );
            // Losses beyond the collisions are still named.
            cap.collision_fragments = Some(1);
            let j = run(&cap, &l, false);
            let want = if tie {
                Flag::LostCoplanar
            } else {
                Flag::Precision
            };
            assert!(j.flags.contains(want), "tie {tie}: {:?}", j.flags);
        }
    }

    #[test]
    fn an_exact_capture_matches_the_truth_and_has_no_vs_k() {
        let l = lists(&[3, 0, 5], false);
        let cap = cap_with(l.composite(), vec![3, 0, 5], Expected::All);
        let j = run(&cap, &l, true);
        assert_eq!(j.matches_truth, Some(true));
        assert!(j.vs_k.is_none() && j.flags.is_empty(), "{:?}", j.flags);
        assert_eq!((j.fragments_missing, j.fragments_extra), (Some(0), Some(0)));
    }

    #[test]
    fn an_exact_method_with_extra_fragments_is_flagged_even_if_the_image_is_close() {
        // compute_abuffer on 10 000 grass blades at 128² once counted 2 fragments beyond the
        // reference's (f32 vertex snapping): the count differs, and it is named.
        let l = lists(&[3, 3], false);
        let cap = cap_with(l.composite(), vec![4, 3], Expected::All);
        let j = run(&cap, &l, true);
        assert!(j.flags.contains(Flag::FragmentsDiffer), "{:?}", j.flags);
        assert_eq!(j.fragments_extra, Some(1));
        let mut row = Row::new();
        j.write(&mut row);
        assert_eq!(row.get(cols::FLAG), Some(Flag::FragmentsDiffer.name()));
        assert_eq!(row.get(cols::FRAGMENTS_EXTRA), Some("1"));
    }

    #[test]
    fn peeling_with_enough_layers_is_held_to_the_whole_fragment_set() {
        // k = 4 ≥ every pixel's 3: the set must be complete; with k = 2 it cannot be.
        let l = lists(&[3, 3], false);
        let cap = cap_with(l.composite(), vec![3, 2], Expected::FirstK(4));
        let j = run(&cap, &l, true);
        assert_eq!(j.fragments_missing, Some(1));
        assert!(j.flags.contains(Flag::FragmentsDiffer), "{:?}", j.flags);
        let cap = cap_with(l.composite_first(2), vec![2, 2], Expected::FirstK(2));
        let j = run(&cap, &l, true);
        assert_eq!(j.fragments_missing, None);
        // Strict peeling's coplanar loss is its definition, flagged as such only.
        let tied = lists(&[3], true);
        let cap = cap_with(tied.composite(), vec![2], Expected::FirstK(8));
        let j = run(&cap, &tied, true);
        assert_eq!(j.fragments_missing, Some(1));
        assert!(j.flags.contains(Flag::LostCoplanar), "{:?}", j.flags);
        assert!(!j.flags.contains(Flag::FragmentsDiffer), "{:?}", j.flags);
    }

    #[test]
    fn losses_at_depth_ties_are_coplanar_and_elsewhere_precision() {
        let tied = lists(&[3], true);
        let cap = cap_with(tied.composite(), vec![2], Expected::All);
        let j = run(&cap, &tied, true);
        assert!(j.flags.contains(Flag::LostCoplanar), "{:?}", j.flags);
        let distinct = lists(&[3], false);
        let cap = cap_with(distinct.composite(), vec![2], Expected::All);
        let j = run(&cap, &distinct, true);
        assert!(j.flags.contains(Flag::Precision), "{:?}", j.flags);
        assert!(j.flags.contains(Flag::FragmentsDiffer));
    }

    #[test]
    fn an_exact_capture_without_counts_and_a_wrong_image_is_flagged_image_differs() {
        // As an MSAA capture: no per-pixel counts, so only the image can show the error.
        let l = lists(&[3, 2], false);
        let mut wrong = l.composite();
        wrong[1] = [0.0; 4];
        let mut cap = cap_with(wrong, vec![], Expected::All);
        cap.counts = None;
        let j = run(&cap, &l, true);
        assert!(j.flags.contains(Flag::ImageDiffers), "{:?}", j.flags);
        // The same image from an approximate method is its error, not a failure.
        assert!(!run(&cap, &l, false).flags.contains(Flag::ImageDiffers));
        // The right image is not flagged.
        cap.image = Some(l.composite().iter().map(|p| p.map(|v| v as f32)).collect());
        assert!(run(&cap, &l, true).flags.is_empty());
        // Nor one whose difference an overflow explains.
        let cap = cap_with(l.composite_first(1), vec![1, 1], Expected::FirstK(1));
        let j = run(&cap, &l, true);
        assert!(!j.flags.contains(Flag::ImageDiffers), "{:?}", j.flags);
    }

    #[test]
    fn a_groups_truth_cache_judges_as_a_fresh_truth_and_composites_once() {
        let l = lists(&[3, 1, 4, 1, 5, 9, 2, 6], false);
        let s = scene();
        let e = EffectConfig::default();
        let cache = TruthCache::default();
        let cx = |truths| Context {
            scene: &s,
            effect: &e,
            exact: true,
            flip: true,
            truths,
        };
        for cap in [
            cap_with(l.composite(), vec![3, 1, 4, 1, 5, 9, 2, 6], Expected::All),
            cap_with(
                l.composite_first(2),
                vec![2, 1, 2, 1, 2, 2, 2, 2],
                Expected::FirstK(2),
            ),
            cap_with(l.composite_first(1), vec![1; 8], Expected::FirstK(1)),
        ] {
            let fresh = judge(&cap, &l, cx(None)).unwrap();
            let cached = judge(&cap, &l, cx(Some(&cache))).unwrap();
            let again = judge(&cap, &l, cx(Some(&cache))).unwrap();
            for j in [&cached, &again] {
                assert_eq!(format!("{:?}", j.truth), format!("{:?}", fresh.truth));
                assert_eq!(format!("{:?}", j.vs_k), format!("{:?}", fresh.vs_k));
                assert_eq!(j.flags, fresh.flags);
                assert_eq!(j.matches_truth, fresh.matches_truth);
                assert_eq!(
                    j.flip.as_ref().map(|f| f.result.mean),
                    fresh.flip.as_ref().map(|f| f.result.mean)
                );
            }
        }
        // The truth (All) and the two truncated definitions (k = 2, 1): three images, each once.
        assert_eq!(cache.len(), 3);
    }

    #[test]
    fn a_method_definition_replaces_the_k_truncated_one() {
        let l = lists(&[4, 4], false);
        let mut cap = cap_with(l.composite(), vec![2, 2], Expected::FirstK(2));
        cap.definition = Some(l.composite());
        let j = run(&cap, &l, false);
        assert!(j.vs_k.unwrap().rmse < 1e-7);
        assert_eq!(j.matches_truth, Some(true));
    }

    #[test]
    fn nan_is_precision_and_not_a_match() {
        let l = lists(&[1], false);
        let mut img = l.composite();
        img[0][1] = f64::NAN;
        let cap = cap_with(img, vec![1], Expected::All);
        let j = run(&cap, &l, true);
        assert_eq!(j.matches_truth, Some(false));
        assert!(j.flags.contains(Flag::Precision));
    }

    #[test]
    fn the_method_own_flag_words_are_kept() {
        let l = lists(&[1], false);
        let mut cap = cap_with(l.composite(), vec![1], Expected::All);
        cap.flag = format!("{}|mystery", Flag::Hazard).parse().unwrap();
        let j = run(&cap, &l, false);
        let mut row = Row::new();
        j.write(&mut row);
        assert_eq!(
            row.get(cols::FLAG),
            Some(format!("{}|mystery", Flag::Hazard).as_str())
        );
    }

    #[test]
    fn flip_is_zero_for_the_truth_and_positive_for_a_wrong_image() {
        let l = lists(&[2; 64], false);
        let s = scene();
        let e = EffectConfig::default();
        let cx = Context {
            scene: &s,
            effect: &e,
            exact: true,
            flip: true,
            truths: None,
        };
        let good = cap_with(l.composite(), vec![2; 64], Expected::All);
        let j = judge(&good, &l, cx).unwrap();
        assert_eq!(j.flip.unwrap().result.mean, 0.0);
        let bad = cap_with(l.composite_first(1), vec![1; 64], Expected::All);
        let j = judge(&bad, &l, cx).unwrap();
        assert!(j.flip.unwrap().result.mean > 0.01);
    }

    #[test]
    fn an_overflowing_capture_within_tolerance_matches_but_is_not_exact() {
        // Issue 32: kbuffer_rmw (heuristics=false, layers=16) on quads(32) overflowed at 27 % of
        // pixels with max_abs_err 0.0010 < bad_pixel_tol, so matches_truth = true; the fragments
        // it dropped make it not exact. Here: 20 layers at 3 of 11 pixels, 16 kept.
        let mut dc = vec![16; 8];
        dc.extend([20, 20, 20]);
        let l = lists(&dc, false);
        let counts: Vec<u32> = dc.iter().map(|&d| d.min(16)).collect();
        let cap = cap_with(l.composite_first(16), counts, Expected::FirstK(16));
        let j = run(&cap, &l, false);
        let e = j.truth.as_ref().unwrap();
        assert!(e.max_abs > 0.0 && e.max_abs < BAD_PIXEL_TOL, "{e:?}");
        assert_eq!(j.matches_truth, Some(true));
        assert_eq!(j.exact, Some(false));
        assert!(j.flags.contains(Flag::Overflow));
        let mut row = Row::new();
        j.write(&mut row);
        assert_eq!(row.get(cols::EXACT), Some("false"));
        assert_eq!(row.get(cols::MATCHES_TRUTH), Some("true"));
    }

    #[test]
    fn merged_fragments_are_not_exact_even_when_the_image_is_close() {
        // bdp/adp on quads(2): RMSE 1.1e-4, "exact yes" once; a collision merged fragments.
        let l = lists(&[2, 2, 2], false);
        let mut img = l.composite();
        img[0][0] += 1e-4;
        let mut cap = cap_with(img, vec![2, 1, 2], Expected::All);
        cap.collision_fragments = Some(1);
        cap.flag.add(Flag::Collision);
        let j = run(&cap, &l, false);
        assert_eq!(j.matches_truth, Some(true));
        assert_eq!(j.exact, Some(false));
    }

    #[test]
    fn an_identical_fragment_set_composited_in_f32_is_exact_within_its_bound() {
        // Depth peeling, linked list, compute A-buffer: every fragment, f32 arithmetic.
        let l = lists(&[16, 0, 5, 16], false);
        let cap = cap_with(l.composite(), vec![16, 0, 5, 16], Expected::All);
        let j = run(&cap, &l, true);
        assert_eq!(j.exact, Some(true), "{:?}", j.flags);
        let b = j.exact_bound.unwrap();
        assert!(b > 1e-6 && b < 1e-4, "16 layers: {b}");
        // An error above the bound (but far below bad_pixel_tol) is not exact.
        let mut img = l.composite();
        img[2][1] += 1e-4;
        let cap = cap_with(img, vec![16, 0, 5, 16], Expected::All);
        let j = run(&cap, &l, true);
        assert_eq!((j.exact, j.matches_truth), (Some(false), Some(true)));
        assert!(!j.flags.contains(Flag::ImageDiffers), "{:?}", j.flags);
    }

    #[test]
    fn fragments_swapped_at_a_depth_tie_are_depth_ties_not_exact_and_not_image_differs() {
        // 8 layers at one depth (a method cannot order them): the image composited in the
        // opposite order differs from the truth by more than bad_pixel_tol, but by no more than
        // the swaps the order bound allows. The truth is ambiguous there: not exact (the H200's
        // compute A-buffer on grass once was, at 0.01–0.04 off the truth), not image_differs.
        let l = lists(&[8, 3], true);
        let mut rev = l.clone();
        rev.frags[..8].reverse();
        let cap = cap_with(rev.composite(), vec![8, 3], Expected::All);
        let j = run(&cap, &l, true);
        assert!(
            j.truth.as_ref().unwrap().max_abs > BAD_PIXEL_TOL,
            "{:?}",
            j.truth
        );
        assert!(!j.flags.contains(Flag::ImageDiffers), "{:?}", j.flags);
        assert!(j.flags.contains(Flag::DepthTies), "{:?}", j.flags);
        assert_eq!((j.exact, j.matches_truth), (Some(false), Some(false)));
        assert_eq!(j.depth_tie_pixels, Some(1));
        assert!(j.exact_bound.unwrap() < 1e-4, "the arithmetic only");
        let mut row = Row::new();
        j.write(&mut row);
        assert_eq!(row.get(cols::DEPTH_TIE_PIXELS), Some("1"));
        assert_eq!(row.get(cols::FLAG), Some(Flag::DepthTies.name()));
        // An approximate method's error there is its approximation, not a tie order.
        let j = run(&cap, &l, false);
        assert!(!j.flags.contains(Flag::DepthTies), "{:?}", j.flags);
        assert_eq!(j.depth_tie_pixels, None);
        // The truth's own order at the tie is exact, with no tie pixel.
        let cap = cap_with(l.composite(), vec![8, 3], Expected::All);
        let j = run(&cap, &l, true);
        assert_eq!((j.exact, j.depth_tie_pixels), (Some(true), Some(0)));
        assert!(j.flags.is_empty(), "{:?}", j.flags);
        // The same reversed image of distinct depths is wrong.
        let d = lists(&[8], false);
        let mut rev = d.clone();
        rev.frags.reverse();
        let cap = cap_with(rev.composite(), vec![8], Expected::All);
        let j = run(&cap, &d, true);
        assert!(j.flags.contains(Flag::ImageDiffers), "{:?}", j.flags);
        assert_eq!(j.exact, Some(false));
    }

    /// One pixel per entry: fragments (depth, red, alpha), green and blue 0.5.
    fn pixels(px: &[&[(f64, f64, f64)]]) -> FragmentLists {
        let mut offsets = vec![0u32];
        let mut frags = Vec::new();
        for p in px {
            for (i, &(z, r, a)) in p.iter().enumerate() {
                frags.push(RefFragment {
                    depth: z,
                    view_z: z * 10.0,
                    color: [r, 0.5, 0.5, a],
                    normal: [0.0, 0.0, 1.0],
                    object_id: i as u32,
                    front_facing: true,
                    prim: i as u32,
                    depth_slope: 0.0,
                });
            }
            offsets.push(frags.len() as u32);
        }
        FragmentLists {
            width: px.len() as u32,
            height: 1,
            reversed_z: false,
            offsets,
            frags,
        }
    }

    #[test]
    fn an_attribute_error_at_near_equal_depths_is_not_a_tie_and_a_swap_is() {
        // Issue 41: on the ogres most `depth_ties` pixels were a fragment's colour off (clip-space
        // attribute weights), admitted by the order bound of near-equal depths around it. Two
        // fragments 1e-7 apart (within DEPTH_TOL: no defined order), red 0.2 and 0.6, α 0.5: the
        // order bound is 0.75 × 0.4 = 0.3. Pixel 0: the nearer one's red 0.01 off (0.005 in the
        // image); pixel 1: the two swapped (0.05 off); pixel 2: no run at all, red 0.01 off.
        let truth = pixels(&[
            &[(0.5, 0.2, 0.5), (0.5 + 1e-7, 0.6, 0.5)],
            &[(0.5, 0.2, 0.5), (0.5 + 1e-7, 0.6, 0.5)],
            &[(0.3, 0.2, 0.5), (0.6, 0.6, 0.5)],
        ]);
        let made = pixels(&[
            &[(0.5, 0.21, 0.5), (0.5 + 1e-7, 0.6, 0.5)],
            &[(0.5, 0.6, 0.5), (0.5 + 1e-7, 0.2, 0.5)],
            &[(0.3, 0.21, 0.5), (0.6, 0.6, 0.5)],
        ]);
        let cap = cap_with(made.composite(), vec![2, 2, 2], Expected::All);
        let b = exact_bounds(&truth.depth_complexity(), Some(&truth));
        assert!(b[0].order > 0.29 && b[2].order == 0.0, "{b:?}");
        let j = run(&cap, &truth, true);
        assert_eq!(j.depth_tie_pixels, Some(1), "only the swap is a tie");
        assert!(j.flags.contains(Flag::DepthTies), "{:?}", j.flags);
        assert!(j.flags.contains(Flag::ImageDiffers), "{:?}", j.flags);
        assert!(
            j.notes.iter().any(|n| n.contains("at 2 pixels")),
            "pixels 0 and 2 differ: {:?}",
            j.notes
        );
        // Under bad_pixel_tol the same colour error is neither a tie nor image_differs: the row
        // says it is not exact and why.
        let small = pixels(&[&[(0.5, 0.202, 0.5), (0.5 + 1e-7, 0.6, 0.5)]]);
        let one = pixels(&[truth
            .pixel(0)
            .iter()
            .map(|f| (f.depth, f.color[0], f.color[3]))
            .collect::<Vec<_>>()
            .as_slice()]);
        let j = run(
            &cap_with(small.composite(), vec![2], Expected::All),
            &one,
            true,
        );
        assert_eq!((j.depth_tie_pixels, j.exact), (Some(0), Some(false)));
        assert!(j.flags.is_empty(), "{:?}", j.flags);
        assert!(j.notes.iter().any(|n| n.contains("not exact: 1 pixels")));
    }

    #[test]
    fn only_orders_of_the_runs_explain_an_error_and_alpha_never_moves() {
        let p = pixels(&[&[
            (0.1, 0.9, 0.3),
            (0.4, 0.1, 0.5),
            (0.4 + 1e-7, 0.5, 0.5),
            (0.4 + 2e-7, 0.8, 0.25),
            (0.7, 0.3, 0.5),
        ]]);
        let f = p.pixel(0);
        let truth = mfx_reference::composite(f.iter());
        let u = 1e-6;
        // Every order of the middle run (3! = 6, searched one by one) is explained; the truth's
        // own order too (the caller asks only beyond the arithmetic).
        for perm in [[1, 2, 3], [3, 2, 1], [2, 1, 3], [1, 3, 2]] {
            let order = [0, perm[0], perm[1], perm[2], 4].map(|k| &f[k]);
            let got = mfx_reference::composite(order.into_iter());
            assert!(tie_order_explains(f, got, truth, u), "{perm:?}");
        }
        // Halfway between two orders, off by more than the arithmetic: no order makes it.
        let swap = mfx_reference::composite([0, 2, 1, 3, 4].map(|k| &f[k]).into_iter());
        let mid = [0, 1, 2, 3].map(|c| 0.5 * (swap[c] + truth[c]));
        assert!(!tie_order_explains(f, mid, truth, u));
        // Moving a fragment outside any run is never an order: the first one's red.
        let mut got = truth;
        got[0] += 0.01 * 0.3;
        assert!(!tie_order_explains(f, got, truth, u));
        // Nor alpha, which no order changes.
        let mut got = truth;
        got[3] += 1e-4;
        assert!(!tie_order_explains(f, got, truth, u));
        // A run too long to search (8! orders): each channel within the range its orders span.
        let long: Vec<(f64, f64, f64)> = (0..8)
            .map(|k| (0.5 + 1e-8 * k as f64, 0.1 * k as f64, 0.4))
            .collect();
        let l = pixels(&[&long]);
        let f = l.pixel(0);
        let truth = mfx_reference::composite(f.iter());
        let rev = mfx_reference::composite(f.iter().rev());
        assert!(tie_order_explains(f, rev, truth, u));
        // Reversed, these colours are the channel's largest: beyond it, no order.
        let mut beyond = rev;
        beyond[0] += 0.01;
        assert!(!tie_order_explains(f, beyond, truth, u));
    }

    #[test]
    fn a_capture_beyond_the_f32_bound_within_tolerance_says_why_it_is_not_exact() {
        // 17 effect rows on the H200 were exact = false with no flag and no word of why.
        let l = lists(&[8], false);
        let mut img = l.composite();
        img[0][0] += 1e-4;
        let j = run(&cap_with(img, vec![8], Expected::All), &l, true);
        assert_eq!((j.exact, j.matches_truth), (Some(false), Some(true)));
        assert!(j.flags.is_empty(), "{:?}", j.flags);
        assert!(
            j.notes
                .iter()
                .any(|n| n.contains("not exact: 1 pixels beyond")),
            "{:?}",
            j.notes
        );
        // An exact capture has no such note.
        let j = run(&cap_with(l.composite(), vec![8], Expected::All), &l, true);
        assert_eq!(j.exact, Some(true));
        assert!(
            !j.notes.iter().any(|n| n.contains("not exact")),
            "{:?}",
            j.notes
        );
    }

    #[test]
    fn exact_implies_matches_truth() {
        // Issue 32: on the H200 the compute A-buffer on grass was exact = true with
        // matches_truth = false (its tie order within an exact_bound of 0.15–0.22). Every
        // capture here, ties or not, within or beyond any bound, keeps exact ⇒ matches_truth.
        let mut caps: Vec<(FragmentLists, Capture)> = Vec::new();
        for tie in [false, true] {
            let l = lists(&[8, 3, 0, 5], tie);
            let counts = vec![8, 3, 0, 5];
            let mut rev = l.clone();
            rev.frags.reverse();
            for img in [l.composite(), rev.composite(), l.composite_first(7)] {
                for nudge in [0.0, 1e-6, 1e-3, 3e-3, 0.1] {
                    let mut img = img.clone();
                    img[0][0] += nudge;
                    caps.push((l.clone(), cap_with(img, counts.clone(), Expected::All)));
                }
            }
        }
        // ~2000 layers: an arithmetic bound (0.0038) above bad_pixel_tol; an error between them.
        let deep = lists(&[2000], false);
        let mut img = deep.composite();
        img[0][1] += 0.003;
        caps.push((deep.clone(), cap_with(img, vec![2000], Expected::All)));
        let mut checked = (0, 0);
        for (l, cap) in &caps {
            let j = run(cap, l, true);
            if j.exact == Some(true) {
                checked.0 += 1;
                assert_eq!(j.matches_truth, Some(true), "{:?} {:?}", j.truth, j.flags);
                assert_eq!(j.depth_tie_pixels, Some(0));
            } else {
                checked.1 += 1;
            }
        }
        assert!(
            checked.0 > 0 && checked.1 > 0,
            "both kinds judged: {checked:?}"
        );
    }

    #[test]
    fn image_differs_is_judged_per_pixel_for_every_method_held_to_a_definition() {
        // Lavapipe's grass: pixel 1 (within capacity) is wrong in every capture; pixel 0
        // overflows in the k-buffer only. The k-buffer (claiming no exactness, overflowing
        // elsewhere) was not flagged while the exact methods were: both are now.
        let l = lists(&[3, 2], false);
        let mut wrong = l.composite_first(2);
        wrong[1] = [0.0; 4];
        let kbuf = cap_with(wrong.clone(), vec![2, 2], Expected::FirstK(2));
        let j = run(&kbuf, &l, false);
        assert!(j.flags.contains(Flag::Overflow), "{:?}", j.flags);
        assert!(j.flags.contains(Flag::ImageDiffers), "{:?}", j.flags);
        let mut exact_img = l.composite();
        exact_img[1] = [0.0; 4];
        let peel = cap_with(exact_img, vec![3, 2], Expected::All);
        assert!(run(&peel, &l, true).flags.contains(Flag::ImageDiffers));
        // A difference only at the overflowing pixel is the overflow's.
        let kbuf = cap_with(l.composite_first(2), vec![2, 2], Expected::FirstK(2));
        assert!(!run(&kbuf, &l, false).flags.contains(Flag::ImageDiffers));
    }
}
