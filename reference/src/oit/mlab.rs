//! Multi-layer alpha blending (Salvi & Vaidyanathan, "Multi-Layer Alpha Blending", I3D 2014,
//! §3 and its Listing 1): each pixel keeps k blend layers (depth, premultiplied colour,
//! transmittance) sorted nearest first. A fragment (z, c, α) becomes the layer (z, α·c, 1 − α)
//! and is inserted behind every layer of smaller or equal depth; if that makes k + 1 layers,
//! the two farthest, n (nearer) and f, merge into one at n's depth:
//!
//! ```text
//! rgb_n ← rgb_n + t_n · rgb_f,   t_n ← t_n · t_f
//! ```
//!
//! The resolve composites the layers nearest first: C = Σᵢ (Πⱼ<ᵢ tⱼ)·rgbᵢ, A = 1 − Πᵢ tᵢ.
//!
//! Properties the tests check: with n ≤ k fragments nothing merges and the result is exact; A is
//! always exact (merging multiplies transmittances); the result is always some permutation of
//! the fragments composited (a merged layer is a block later fragments cannot enter), so colour
//! stays a convex combination of the fragment colours times A; and it depends on arrival order:
//! nearest-first or farthest-first arrival is exact for any n, a fragment arriving between two
//! already-merged ones is composited behind both.

use super::{to_f64, Frag, Order, Real};
use crate::RefFragment;

/// One blend layer: depth, premultiplied colour, transmittance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer<T> {
    pub z: T,
    pub rgb: [T; 3],
    pub trans: T,
}

/// A twin's answer with the number of overflow events it handled (merges, node removals).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layered<T> {
    /// Premultiplied RGB, A = 1 − transmittance.
    pub rgba: [T; 4],
    /// Overflow events: merges for MLAB (max(0, n − k)), node removals for adaptive.
    pub merges: u32,
}

/// The k blend layers after inserting `frags` in the given (arrival) order, and the merge count.
/// Panics if k = 0.
pub fn blend_layers<T: Real>(frags: &[Frag<T>], k: usize) -> (Vec<Layer<T>>, u32) {
    assert!(k >= 1, "MLAB needs at least one layer");
    let mut layers: Vec<Layer<T>> = Vec::with_capacity(k + 1);
    let mut merges = 0;
    for f in frags {
        let a = f.alpha();
        let layer = Layer {
            z: f.z,
            rgb: [a * f.color[0], a * f.color[1], a * f.color[2]],
            trans: T::ONE - a,
        };
        // Behind every layer at a smaller or equal depth (the listing's strict `<` swap).
        let at = layers.iter().take_while(|l| l.z <= f.z).count();
        layers.insert(at, layer);
        if layers.len() > k {
            let far = layers.pop().expect("k + 1 layers");
            let near = layers.last_mut().expect("k ≥ 1 layers");
            for (n, f) in near.rgb.iter_mut().zip(far.rgb) {
                *n += near.trans * f;
            }
            near.trans *= far.trans;
            merges += 1;
        }
    }
    (layers, merges)
}

/// Composites blend layers nearest first.
pub fn resolve<T: Real>(layers: &[Layer<T>]) -> [T; 4] {
    let mut c = [T::ZERO; 3];
    let mut t = T::ONE;
    for l in layers {
        for (ci, li) in c.iter_mut().zip(l.rgb) {
            *ci += t * li;
        }
        t *= l.trans;
    }
    [c[0], c[1], c[2], T::ONE - t]
}

/// MLAB with k layers over `frags` in arrival order, at precision `T`.
pub fn mlab_t<T: Real>(frags: &[Frag<T>], k: usize) -> Layered<T> {
    let (layers, merges) = blend_layers(frags, k);
    Layered {
        rgba: resolve(&layers),
        merges,
    }
}

/// MLAB with k layers; `frags` in the order they arrive (e.g. [`super::Order::Arrival`]).
pub fn mlab(frags: &[RefFragment], k: usize) -> [f64; 4] {
    mlab_merges(frags, k).0
}

/// [`mlab`] and the number of merges it made.
pub fn mlab_merges(frags: &[RefFragment], k: usize) -> ([f64; 4], u32) {
    let f: Vec<Frag<f64>> = frags.iter().map(Frag::of).collect();
    let r = mlab_t(&f, k);
    (to_f64(r.rgba), r.merges)
}

/// MLAB of one reference pixel (nearest first, as [`crate::FragmentLists`] stores
/// it) replayed in `order`.
pub fn mlab_pixel(list: &[RefFragment], k: usize, order: Order) -> ([f64; 4], u32) {
    let r = mlab_t(&super::frags::<f64>(list, order), k);
    (to_f64(r.rgba), r.merges)
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;
    use rand::Rng;

    #[test]
    fn mlab_is_exact_when_depth_complexity_is_at_most_k() {
        let mut rng = rng(11);
        for k in [1usize, 2, 4, 8] {
            for n in 0..=k {
                for _ in 0..20 {
                    let px = pixel(&mut rng, n, 0.05, 0.95, 1.0, 10.0);
                    let (got, merges) = mlab_merges(&arrival(&px), k);
                    assert_eq!(merges, 0);
                    // Same products in the same depth order as the reference: rounding only.
                    assert!(max_abs(got, exact(&px)) < 1e-12, "k {k} n {n}");
                }
            }
        }
    }

    #[test]
    fn mlab_alpha_is_exact_and_colour_a_convex_combination_for_any_n() {
        let mut rng = rng(12);
        for k in [1usize, 2, 4, 8] {
            for _ in 0..100 {
                let n = rng.random_range(0..64);
                let px = pixel(&mut rng, n, 0.02, 0.95, 1.0, 10.0);
                let (got, merges) = mlab_merges(&arrival(&px), k);
                assert_eq!(merges as usize, n.saturating_sub(k));
                let want = exact(&px);
                assert_valid(got, "mlab");
                // A = 1 − Π tᵢ however the layers merged.
                assert!((got[3] - want[3]).abs() < 1e-12);
                // Both are Σ wᵢ cᵢ with Σ wᵢ = A: per channel within (max c − min c)·A.
                for ch in 0..3 {
                    let (lo, hi) = px.iter().fold((1.0f64, 0.0f64), |(lo, hi), f| {
                        (lo.min(f.color[ch]), hi.max(f.color[ch]))
                    });
                    assert!((got[ch] - want[ch]).abs() <= (hi - lo) * want[3] + 1e-12);
                }
            }
        }
    }

    #[test]
    fn mlab_is_exact_for_monotone_arrival_and_order_dependent_otherwise() {
        let mut rng = rng(13);
        for _ in 0..50 {
            let px = pixel(&mut rng, 40, 0.05, 0.9, 1.0, 10.0);
            let want = exact(&px);
            // Nearest first: each fragment merges at the back. Farthest first: merged layers
            // are always behind every later fragment. Either way no layer is ever split.
            assert!(max_abs(mlab(&px, 2), want) < 1e-12);
            let rev: Vec<_> = px.iter().rev().copied().collect();
            assert!(max_abs(mlab(&rev, 2), want) < 1e-12);
        }
        // k = 1: A (z 1) and C (z 3) merge; B (z 2) then lands behind the block [A C].
        let a = frag(1.0, [1.0, 0.0, 0.0, 0.5], 0);
        let b = frag(2.0, [0.0, 1.0, 0.0, 0.5], 1);
        let c = frag(3.0, [0.0, 0.0, 1.0, 0.5], 2);
        let got = mlab(&[a, c, b], 1);
        let want = exact(&[a, b, c]);
        // Composited as A, C, B instead of A, B, C: green and blue swap weights 0.25 ↔ 0.125.
        assert!(
            (got[1] - 0.125).abs() < 1e-12 && (got[2] - 0.25).abs() < 1e-12,
            "{got:?}"
        );
        assert!((want[1] - 0.25).abs() < 1e-12 && (want[2] - 0.125).abs() < 1e-12);
    }

    #[test]
    fn mlab_f32_twin_follows_f64_to_1e5() {
        // What a GPU test comparing an f32 MLAB with this twin can expect from rounding alone.
        let mut rng = rng(14);
        for _ in 0..200 {
            let px = arrival(&pixel(&mut rng, 300, 0.02, 0.3, 1.0, 10.0));
            let f32s: Vec<Frag<f32>> = px.iter().map(Frag::of).collect();
            let got = to_f64(mlab_t(&f32s, 4).rgba);
            assert!(max_abs(got, mlab(&px, 4)) < 1e-5);
        }
    }
}
