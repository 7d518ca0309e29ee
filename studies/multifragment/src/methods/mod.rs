//! Multi-fragment methods: the table of contents.
//!
//! | name           | source                         | exact?                     | geometry passes | memory per pixel          |
//! |----------------|--------------------------------|----------------------------|-----------------|---------------------------|
//! | `floor_depth`  | the yardstick (issue "Compare GPUs") | — (no image)          | 1               | 4 B depth                 |
//! | `floor_depth_vs` | the old `floor_depth`: no fragment stage (its time followed the last render pipeline run) | — (no image) | 1         | 4 B depth                 |
//! | `floor_opaque` | the yardstick, one colour       | — (no image)              | 1               | 4 B depth + 4 B RGBA8     |
//! | `floor_blend`  | unsorted transparency through the methods' own vertex stage (every attribute, each fragment's colour) | — (not judged: primitive order) | 1 | 4 B RGBA8 |
//! | `floor_blend_const` | the yardstick of `x_blend` (LucidRaster's ratio): the cheapest unsorted blend, positions only and one colour | — (not judged) | 1 | 4 B RGBA8 |
//! | `depth_peel`   | Everitt 2001, classic front-to-back peeling; every effect via the fold | exact up to `max_layers`; coplanar ties lost (`variant=tiebreak` keeps them) | layers + 1 | 2×4 B depth + 4–36 B layer payload + 64 B fold state + 16 B per output image + 4 B count |
//! | `dual_peel`    | Bavoil & Myers 2008, dual depth peeling (MAX blending, nearest + farthest per pass) | exact up to `max_layers`; coplanar ties merged | ⌈layers/2⌉ + 1 | 2×8 B depth + 2×16 B layers + 2×16 B accumulation + 16 B image + 4 B count |
//! | `kbuffer_rmw`  | Bavoil 2007 ch. 4, k-buffer by non-atomic read-modify-write insertion; every effect via the fold | k nearest, but RMW hazards (measured: `hazard_rate`) | 1 (+ resolve) | k × (4 B key + 4–32 B entry: the effect's payload, or all with `specialisation = uber`) + 16 B per output image |
//! | `kbuffer_atomic` | hazard-free k-buffer: 32-bit atomicMax bubbling of depth keys, then a payload pass; every effect via the fold | exact k nearest (ties get their own slots) | 2 (+ resolve) | k × (4 B key + 4 B claim + 4–32 B entry) + 16 B per output image |
//!
//! The bounded captures `kbuffer_rmw`, `kbuffer_atomic` and `linked_list` also take `tail =
//! drop|blend` (what does not fit is dropped, or blended out of order into a tail composited
//! behind the kept fragments: `tail`, 24 B per pixel of blend targets) and the k-buffers `keep =
//! nearest|first`; the defaults are their original behaviour.
//!
//! | `linked_list`  | Yang et al. 2010, per-pixel linked lists (atomic heads; per-8×8-tile node pools counted at prepare, or one layers × pixels pool), sorted in the resolve; compact nodes re-derived per primitive | exact within the pool; overflow counted | 1 (+ resolve) | 32 B (head, lost, count, image, stand-in depth) + 12 B per true fragment (compact, counted; 32 B full nodes, or layers × nodes when fixed) |
//! | `compute_abuffer` | Maule et al. 2012 dynamic fragment buffer, rasterised in compute (no render pass; Laine & Karras 2011 in spirit), attributes re-derived per primitive (visibility buffer) | exact: coverage rule for rule as the reference, sized by a prepare-time count; lists over 128 counted | 2 (count, fill) + scan + resolve | 4 B offset + 16 B image + exactly 8 B per fragment (+ 24 B per vertex with `transform = vertex`) |
//! | `wboit`        | McGuire & Bavoil 2013, weighted blended OIT | approximate (exact for one layer or one colour/alpha) | 1 (+ resolve) | 8 B RGBA16F + 2 B R16F + 16 B result (× samples for the targets under MSAA) |
//! | `moments`      | Münstermann et al. 2018, moment-based OIT: b₀ + 4/6/8 power or 2/3/4 trigonometric moments, f32 blending or the paper's unorm16 (unguarded RMW), reconstruction per fragment, optional normalisation | approximate (exact for one layer, normalised); failed f32 reconstructions counted (flag precision) | 2 (+ composite) | 4 B b₀ + 4 B (2 B) per moment + 16 B sum + 16 B image |
//! | `mlab`         | Salvi & Vaidyanathan 2014, multi-layer alpha blending by unguarded RMW (no ROVs); `tail = merge\|drop\|blend` | approximate (exact for n ≤ k); races measured vs the ideal-order twin (`hazard_rate`) | 1 (+ resolve) | k × 20 B + 4 B count + 16 B image (+ 24 B tail) |
//! | `mlab_ideal`   | MLAB as ordering hardware gives it: compute_abuffer's capture replayed per pixel in primitive order | approximate (exact for n ≤ k); separates MLAB's error from the race | compute_abuffer's | 8 B per fragment + compute_abuffer's |
//! | `adaptive`     | Salvi et al. 2011, adaptive transparency: k visibility nodes by unguarded RMW, least-area removal, shading pass | approximate (exact for n ≤ k; darkens); races measured vs the ideal-order twin | 2 (+ composite) | k × 8 B + 4 B count + 16 B sum + 16 B image |
//! | `adaptive_ideal` | adaptive transparency replayed in primitive order from compute_abuffer's capture | approximate (exact for n ≤ k) | compute_abuffer's | 8 B per fragment + compute_abuffer's |
//! | `hybrid`       | Maule et al. 2013, hybrid transparency: the atomic k-buffer's k nearest exact + a mean-alpha weighted tail behind them | approximate (exact for n ≤ k), order-independent | 2 (+ resolve) | k × 40 B + 16 B image + 24 B tail |
//! | `stochastic`   | Enderton et al. 2010 stochastic transparency (random α·S sample masks, MSAA depth test, passes averaged, alpha correction) | approximate: unbiased without the correction, noise ∝ 1/√(S·passes); judged vs the S-sample truth | 2 per pass (+1 for the correction) | S × (4 B depth + 16 B RGBA32F + 4 B R32F) + 32 B |
//! | `bdp`          | Liu et al., GPU Pro ch. 1, uniform bucket depth peeling; transparency, and translucency / fresnel on (depth, normal) bucket pairs | approximate: exact iff ≤1 fragment per bucket (2 if paired); collisions counted | 2 | 8 B range + 4 B × channels (≤32) + 68 B resolve |
//! | `bdp2`         | Liu et al., GPU Pro ch. 1, two-pass BDP; `bucket_pairing = paired` is §1.4's (a pair per bucket a pass) | approximate: 2 fragments per bucket (4 paired); collisions counted | 3 | 8 B range + 2 × 4 B × channels + 68 B resolve |
//! | `bdpn`         | Liu et al., GPU Pro ch. 1 §1.4, multi-pass BDP: bucket pairs until an occlusion query counts nothing | approximate: exact up to RGBA6 unless two fragments share an in-bucket key; collisions counted | 1 + passes + 1 | 8 B range + 2 × 8 B × K + 8 B × K × max_layers + 68 B resolve |
//! | `adp`          | Liu et al., GPU Pro ch. 1, adaptive (histogram-equalised) BDP; `bucket_pairing = paired`: a (near, far) pair per occupied bin (§1.5) | approximate: fragments sharing a histogram bin collide (a third, paired) | 2 + ⌈occupied bins / K⌉ | hist_bins/8 B + 8 B × K + 8 B range + 68 B resolve |
//!
//! Every method implements [`Method`] (what it is, which axes and features it needs, and
//! `prepare`, which creates every GPU object) and [`Prepared`] (`frame`, the timed per-frame
//! work, and `readback`). Nothing assumes a render pass: a compute-only method only has to fill
//! the same [`Capture`]. Antialiasing (`aa`, `aa_capture`: `crate::aa`) is declared per method:
//! `depth_peel` (per sample), `wboit` (both), `compute_abuffer` (coverage masks), each of them
//! also under `ssaa2x2` (`shared::ssaa`), `linked_list` (a list per sample, or coverage-mask compact
//! nodes, and `ssaa2x2`), `kbuffer_atomic` (k slots per sample, and `ssaa2x2`; no coverage
//! k-buffer: its k nearest per pixel have no per-sample rule), and `stochastic` (MSAA by
//! construction);
//! the rest are `skipped` rows with the reason. The shared vertex stage is `common.wgsl`, prepended to each method's WGSL;
//! `effects.wgsl` ([`FOLD_WGSL`]) is the effects fold. Pieces several methods build on (k slots,
//! the counted capture, tails, buckets, packing, the bind table) live in [`shared`], named for
//! what they are; no method folder imports another (tested: `tests/method_graph.rs`), and the
//! yardsticks are the harness's [`bench_core::floors`], listed here as methods ([`floors`]). The approximate (continuum) methods' per-pixel rules have CPU
//! twins in [`mfx_reference::oit`], which `Prepared::judge` runs on the reference fragments to fill
//! `Capture.definition` (judged into `*_vs_k`).

pub mod adaptive;
pub mod adp;
pub mod bdp;
pub mod bdp2;
pub mod bdpn;
pub mod compute_abuffer;
pub mod depth_peel;
pub mod dual_peel;
pub mod floors;
pub mod hybrid;
pub mod kbuffer_atomic;
pub mod kbuffer_rmw;
pub mod linked_list;
pub mod mlab;
pub mod moments;
pub mod shared;
pub mod stochastic;
pub mod wboit;

pub use crate::method::{supports, Capture, Expected, FrameStats, Method, Prepared, Timed};
use bench_core::floors::Floor;

/// Every method, in listing order.
pub fn all() -> Vec<Box<dyn Method>> {
    vec![
        Box::new(floors::FloorMethod(Floor::Depth)),
        Box::new(floors::FloorMethod(Floor::DepthVs)),
        Box::new(floors::FloorMethod(Floor::Opaque)),
        Box::new(floors::FloorMethod(Floor::Blend)),
        Box::new(floors::FloorMethod(Floor::BlendConst)),
        Box::new(depth_peel::DepthPeel),
        Box::new(dual_peel::DualPeel),
        Box::new(kbuffer_rmw::KBufferRmw),
        Box::new(kbuffer_atomic::KBufferAtomic),
        Box::new(linked_list::LinkedList),
        Box::new(compute_abuffer::ComputeAbuffer),
        Box::new(wboit::Wboit),
        Box::new(moments::Moments),
        Box::new(mlab::Mlab),
        Box::new(mlab::MlabIdeal),
        Box::new(adaptive::Adaptive),
        Box::new(adaptive::AdaptiveIdeal),
        Box::new(hybrid::Hybrid),
        Box::new(stochastic::Stochastic),
        Box::new(bdp::Bdp),
        Box::new(bdp2::Bdp2),
        Box::new(bdpn::Bdpn),
        Box::new(adp::Adp),
    ]
}

pub fn by_name(name: &str) -> Option<Box<dyn Method>> {
    all().into_iter().find(|m| m.name() == name)
}

/// The method called `name`; panics naming the known ones (for tests and fixed tables).
pub fn get(name: &str) -> Box<dyn Method> {
    by_name(name).unwrap_or_else(|| {
        panic!(
            "no method '{name}' (known: {})",
            all()
                .iter()
                .map(|m| m.name())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

/// Tests that hold one method against another on the same scene: the registry sees every
/// method, a method folder sees none but its own.
#[cfg(test)]
mod tests {
    use super::shared::bucket::testing::{quads_at, run};
    use super::shared::bucket::{Config, Kind};
    use super::{adp, bdp};

    #[test]
    fn adp_beats_bdp_on_clustered_depths_48px() {
        // Six layers within 0.25 world units, one far in front and one far behind: uniform
        // buckets put the cluster in one or two buckets, equalised ones give each its own.
        let scene = quads_at(&[3.0, 0.25, 0.2, 0.15, 0.1, 0.05, 0.0, -3.0], 0.4);
        let cfg = Config {
            kind: Kind::Adaptive {
                hist_bins: 1024,
                paired: false,
            },
            buckets: 8,
        };
        let a = run(cfg, adp::tests_wgsl(), &scene, 48);
        let adp_lost = a.assert_counts_match_twin(&cfg);
        let uniform = Config {
            kind: Kind::Uniform { paired: false },
            buckets: 8,
        };
        let b = run(uniform, bdp::tests_wgsl(), &scene, 48);
        let bdp_lost = b.assert_counts_match_twin(&uniform);
        assert!(
            bdp_lost > 0,
            "precondition: the cluster collides in uniform buckets"
        );
        assert!(adp_lost < bdp_lost, "adp lost {adp_lost}, bdp {bdp_lost}");
    }
}
