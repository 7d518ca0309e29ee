//! Weighted blended OIT (McGuire & Bavoil, JCGT 2013), the twin of `methods/wboit`: one
//! weighted sum of premultiplied colour and alpha, w(z, α) = α·clamp(10 / (1e-5 + (z/5)² +
//! (z/200)⁶), 1e-2, 3e3) (the paper's eq. 7, of view distance z), and the revealage Π(1 − α).
//! Resolve: C = (Σ w·α·c / max(Σ w·α, 1e-5))·(1 − Π(1 − α)), A = 1 − Π(1 − α).
//!
//! The GPU keeps the sums in RGBA16F and the revealage in R16F; [`wboit_t`] with
//! [`Storage::F16`] rounds after every blend as those targets do. Exact for one fragment, or when
//! all fragments share one colour; order-independent up to summation rounding.

use super::{to_f64, Frag, Real, Storage};
use crate::RefFragment;

/// The paper's eq. 7 weight, as `methods/wboit/wboit.wgsl` computes it (z = |view z|).
pub fn weight<T: Real>(z: T, alpha: T) -> T {
    let z = z.abs();
    let d = T::of(1e-5) + (z / T::of(5.0)) * (z / T::of(5.0)) + (z / T::of(200.0)).powf(T::of(6.0));
    alpha * (T::of(10.0) / d).clamp(T::of(1e-2), T::of(3e3))
}

/// WBOIT at precision `T`, sums stored as `storage` between fragments (in the given order).
pub fn wboit_t<T: Real>(frags: &[Frag<T>], storage: Storage) -> [T; 4] {
    let mut acc = [T::ZERO; 4];
    let mut reveal = T::ONE;
    for f in frags {
        let a = f.alpha();
        let w = weight(f.z, a);
        let src = [
            f.color[0] * a * w,
            f.color[1] * a * w,
            f.color[2] * a * w,
            a * w,
        ];
        for (s, v) in acc.iter_mut().zip(src) {
            *s = storage.round(*s + v);
        }
        reveal = storage.round(reveal * (T::ONE - a));
    }
    let a = T::ONE - reveal;
    let d = acc[3].max(T::of(1e-5));
    [acc[0] / d * a, acc[1] / d * a, acc[2] / d * a, a]
}

/// WBOIT in f64 (fragments in any order).
pub fn wboit(frags: &[RefFragment]) -> [f64; 4] {
    let f: Vec<Frag<f64>> = frags.iter().map(Frag::of).collect();
    to_f64(wboit_t(&f, Storage::Native))
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;
    use rand::Rng;

    #[test]
    fn wboit_is_exact_for_one_fragment_and_for_one_colour() {
        // α ≥ 0.05 and z ≤ 50 keep Σ w·α ≥ 2.5e-4 above the resolve's 1e-5 floor, below which
        // WBOIT is not exact even for one fragment.
        let mut rng = rng(61);
        for _ in 0..50 {
            let px = pixel(&mut rng, 1, 0.05, 1.0, 0.5, 50.0);
            assert!(max_abs(wboit(&px), exact(&px)) < 1e-12);
            // Every fragment one colour: the weighted average is that colour.
            let mut px = pixel(&mut rng, 20, 0.05, 0.95, 0.5, 50.0);
            let c = px[0].color;
            px.iter_mut()
                .for_each(|f| f.color[..3].copy_from_slice(&c[..3]));
            assert!(max_abs(wboit(&px), exact(&px)) < 1e-12);
        }
    }

    #[test]
    fn wboit_alpha_is_exact_colour_bounded_and_order_independent() {
        let mut rng = rng(62);
        for _ in 0..100 {
            let n = rng.random_range(1..80);
            let px = pixel(&mut rng, n, 0.02, 0.95, 0.5, 50.0);
            let got = wboit(&arrival(&px));
            let want = exact(&px);
            assert_valid(got, "wboit");
            assert!((got[3] - want[3]).abs() < 1e-12);
            // A weighted average of the colours times A, like the exact result.
            for ch in 0..3 {
                let (lo, hi) = px.iter().fold((1.0f64, 0.0f64), |(lo, hi), f| {
                    (lo.min(f.color[ch]), hi.max(f.color[ch]))
                });
                assert!((got[ch] - want[ch]).abs() <= (hi - lo) * want[3] + 1e-12);
            }
            assert!(
                max_abs(got, wboit(&px)) < 1e-12,
                "arrival order does not matter"
            );
        }
    }

    #[test]
    fn wboit_f16_storage_stays_near_f32() {
        // Half-float sums: ~2⁻¹¹ relative per add; 40 fragments stay within a few 1e-3.
        let mut rng = rng(63);
        for _ in 0..100 {
            let px = arrival(&pixel(&mut rng, 40, 0.05, 0.5, 1.0, 20.0));
            let f: Vec<Frag<f32>> = px.iter().map(Frag::of).collect();
            let h = to_f64(wboit_t(&f, Storage::F16));
            let s = to_f64(wboit_t(&f, Storage::Native));
            assert!(max_abs(h, s) < 1e-2, "{h:?} {s:?}");
        }
    }
}
