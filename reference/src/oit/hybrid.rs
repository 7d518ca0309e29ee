//! Hybrid transparency (Maule, Comba, Torchelsen & Bastos, "Hybrid Transparency", I3D 2013):
//! the k nearest fragments of a pixel (the core, an atomic k-buffer's content) are composited
//! exactly, nearest first; the rest (the tail) are accumulated order-independently and
//! composited behind the core. The tail uses the weighted average of Bavoil & Myers (2008) that
//! the paper builds on: colour Σαᵢcᵢ / Σαᵢ, opacity 1 − (1 − ᾱ)ⁿ with ᾱ = Σαᵢ / n over the n tail
//! fragments:
//!
//! ```text
//! C = C_core + T_core · A_tail · Σαᵢcᵢ / Σαᵢ,     A = 1 − T_core · (1 − A_tail)
//! ```
//!
//! Unlike [`super::tail_blend`] (exact tail opacity Π(1 − α)), the tail's opacity here is an
//! estimate from the mean alpha, never above the exact one (AM–GM), so A can be low where tail
//! alphas vary. Order-independent: the core is the k nearest whatever the arrival order.

use super::tail::{behind, split, Keep, TailSums};
use super::{composite_sorted, to_f64, Frag, Real};
use crate::RefFragment;

/// Hybrid transparency with a core of k at precision `T` (fragments in any order). Also returns
/// the number of tail fragments.
pub fn hybrid_t<T: Real>(frags: &[Frag<T>], k: usize) -> ([T; 4], u32) {
    let (core, rest) = split(frags, k, Keep::Nearest);
    let (c, t) = composite_sorted(core.iter().map(|&i| &frags[i]));
    let mut sums = TailSums::default();
    for &i in &rest {
        sums.add(&frags[i]);
    }
    let opacity = sums.mean_alpha_opacity();
    (
        behind(c, t, sums.premultiplied(opacity), opacity),
        sums.count,
    )
}

/// Hybrid transparency with a core of k fragments.
pub fn hybrid(frags: &[RefFragment], k: usize) -> [f64; 4] {
    let f: Vec<Frag<f64>> = frags.iter().map(Frag::of).collect();
    to_f64(hybrid_t(&f, k).0)
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;
    use rand::Rng;

    #[test]
    fn hybrid_is_exact_when_depth_complexity_is_at_most_k() {
        let mut rng = rng(51);
        for k in [1usize, 2, 4, 8] {
            for n in 0..=k {
                let px = pixel(&mut rng, n, 0.05, 0.95, 1.0, 10.0);
                assert!(max_abs(hybrid(&arrival(&px), k), exact(&px)) < 1e-12);
            }
        }
    }

    #[test]
    fn hybrid_equal_alpha_tail_is_exact_in_alpha_and_bounded_in_colour() {
        let mut rng = rng(52);
        for _ in 0..100 {
            let n = rng.random_range(0..60);
            // One opacity for every fragment: (1 − ᾱ)ⁿ = Π(1 − α), so A is exact.
            let a = rng.random_range(0.02..0.9);
            let px = pixel(&mut rng, n, a, a, 1.0, 10.0);
            let got = hybrid(&arrival(&px), 4);
            let want = exact(&px);
            assert_valid(got, "hybrid");
            assert!((got[3] - want[3]).abs() < 1e-12);
            // Then colour is Σ wᵢcᵢ with Σ wᵢ = A, like the exact one: within (max − min c)·A.
            for ch in 0..3 {
                let (lo, hi) = px.iter().fold((1.0f64, 0.0f64), |(lo, hi), f| {
                    (lo.min(f.color[ch]), hi.max(f.color[ch]))
                });
                assert!((got[ch] - want[ch]).abs() <= (hi - lo) * want[3] + 1e-12);
            }
        }
    }

    #[test]
    fn hybrid_is_order_independent_and_never_more_opaque_than_exact() {
        let mut rng = rng(53);
        for _ in 0..100 {
            let n = rng.random_range(0..60);
            let px = pixel(&mut rng, n, 0.02, 0.95, 1.0, 10.0);
            let a = hybrid(&arrival(&px), 4);
            assert!(max_abs(a, hybrid(&px, 4)) < 1e-12);
            assert_valid(a, "hybrid");
            assert!(
                a[3] <= exact(&px)[3] + 1e-12,
                "mean-alpha tail opacity ≤ exact"
            );
        }
    }
}
