//! Bounded captures with a tail (NVIDIA's vk_order_independent_transparency "tail blend"
//! switch; Bevy's OIT lists it as a TODO and drops overflowing fragments): a method that keeps
//! k fragments per pixel (`kbuffer_rmw`, `kbuffer_atomic`, a linked list with a fixed pool,
//! MLAB) composites the kept ones exactly, nearest first, and the fragments that did not fit
//! are either dropped or blended order-independently into a tail composited behind them.
//!
//! Which k are kept: `Keep::Nearest` (a k-buffer's k nearest; a fragment evicted later goes to
//! the tail then) or `Keep::First` (the first k to arrive, as a fixed pool fills).
//!
//! Tail (`TailMode::Blend`), three order-independent sums a blend unit can keep:
//! Σ αᵢcᵢ, Σ αᵢ and T_tail = Π(1 − αᵢ). Its colour is the alpha-weighted average and its
//! opacity exact, composited behind the kept fragments' transmittance T_kept:
//!
//! ```text
//! C = C_kept + T_kept · (1 − T_tail) · Σαᵢcᵢ / Σαᵢ,     A = 1 − T_kept · T_tail
//! ```
//!
//! So A is exact whatever is kept, and with `Keep::Nearest` the only error is the tail's
//! internal order (its colour is an average instead of a composite).

use super::{composite_sorted, depth_order, to_f64, Frag, Real};
use crate::RefFragment;

/// Which k fragments a bounded capture keeps exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Keep {
    /// The k nearest (a k-buffer). Ties in depth keep the earlier arrival.
    Nearest,
    /// The first k to arrive (a fixed pool).
    First,
}

/// What happens to the fragments that did not fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TailMode {
    Drop,
    Blend,
}

impl Keep {
    pub fn name(self) -> &'static str {
        match self {
            Keep::Nearest => "nearest",
            Keep::First => "first",
        }
    }
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "nearest" => Some(Keep::Nearest),
            "first" => Some(Keep::First),
            _ => None,
        }
    }
}

impl TailMode {
    pub fn name(self) -> &'static str {
        match self {
            TailMode::Drop => "drop",
            TailMode::Blend => "blend",
        }
    }
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "drop" => Some(TailMode::Drop),
            "blend" => Some(TailMode::Blend),
            _ => None,
        }
    }
}

/// A bounded capture's answer and what happened to the fragments that did not fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounded<T> {
    /// Premultiplied RGB, A = 1 − transmittance.
    pub rgba: [T; 4],
    /// Fragments discarded (`TailMode::Drop`).
    pub dropped: u32,
    /// Fragments blended into the tail (`TailMode::Blend`).
    pub tailed: u32,
}

/// The order-independent tail sums: Σ αc, Σ α, Π(1 − α) and the count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TailSums<T> {
    pub weighted_rgb: [T; 3],
    pub alpha_sum: T,
    pub trans: T,
    pub count: u32,
}

impl<T: Real> Default for TailSums<T> {
    fn default() -> Self {
        TailSums {
            weighted_rgb: [T::ZERO; 3],
            alpha_sum: T::ZERO,
            trans: T::ONE,
            count: 0,
        }
    }
}

impl<T: Real> TailSums<T> {
    pub fn add(&mut self, f: &Frag<T>) {
        let a = f.alpha();
        for (s, c) in self.weighted_rgb.iter_mut().zip(&f.color) {
            *s += a * *c;
        }
        self.alpha_sum += a;
        self.trans *= T::ONE - a;
        self.count += 1;
    }

    /// Premultiplied tail colour for the opacity `opacity`: opacity · Σαc / Σα (0 when Σα = 0).
    pub fn premultiplied(&self, opacity: T) -> [T; 3] {
        if self.alpha_sum > T::ZERO {
            self.weighted_rgb.map(|s| opacity * s / self.alpha_sum)
        } else {
            [T::ZERO; 3]
        }
    }

    /// The tail's opacity from the exact product: 1 − Π(1 − α).
    pub fn exact_opacity(&self) -> T {
        T::ONE - self.trans
    }

    /// Bavoil & Myers' (2008) weighted-average opacity: 1 − (1 − ᾱ)ⁿ with ᾱ = Σα / n.
    pub fn mean_alpha_opacity(&self) -> T {
        if self.count == 0 {
            return T::ZERO;
        }
        let n = T::of(self.count as f64);
        T::ONE - (T::ONE - self.alpha_sum / n).powf(n)
    }
}

/// Composites a tail of premultiplied colour `tail_rgb` and opacity `tail_opacity` behind the
/// kept fragments' composite `kept` (whose transmittance is `t_kept`).
pub fn behind<T: Real>(kept: [T; 4], t_kept: T, tail_rgb: [T; 3], tail_opacity: T) -> [T; 4] {
    [
        kept[0] + t_kept * tail_rgb[0],
        kept[1] + t_kept * tail_rgb[1],
        kept[2] + t_kept * tail_rgb[2],
        T::ONE - t_kept * (T::ONE - tail_opacity),
    ]
}

/// Indices of the kept fragments (nearest first) and of the rest, for `frags` in arrival order.
pub fn split<T: Real>(frags: &[Frag<T>], k: usize, keep: Keep) -> (Vec<usize>, Vec<usize>) {
    match keep {
        Keep::Nearest => {
            let order = depth_order(frags);
            let rest = order[k.min(order.len())..].to_vec();
            let mut kept = order;
            kept.truncate(k);
            (kept, rest)
        }
        Keep::First => {
            let n = k.min(frags.len());
            let mut kept: Vec<usize> = (0..n).collect();
            kept.sort_by(|&a, &b| {
                frags[a]
                    .z
                    .partial_cmp(&frags[b].z)
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
            (kept, (n..frags.len()).collect())
        }
    }
}

/// A bounded capture of k fragments at precision `T`; `frags` in arrival order.
pub fn tail_blend_t<T: Real>(
    frags: &[Frag<T>],
    k: usize,
    keep: Keep,
    tail: TailMode,
) -> Bounded<T> {
    let (kept, rest) = split(frags, k, keep);
    let (c, t) = composite_sorted(kept.iter().map(|&i| &frags[i]));
    match tail {
        TailMode::Drop => Bounded {
            rgba: c,
            dropped: rest.len() as u32,
            tailed: 0,
        },
        TailMode::Blend => {
            let mut sums = TailSums::default();
            for &i in &rest {
                sums.add(&frags[i]);
            }
            let opacity = sums.exact_opacity();
            Bounded {
                rgba: behind(c, t, sums.premultiplied(opacity), opacity),
                dropped: 0,
                tailed: rest.len() as u32,
            }
        }
    }
}

/// A bounded capture of k fragments; `frags` in arrival order.
pub fn tail_blend(frags: &[RefFragment], k: usize, keep: Keep, tail: TailMode) -> Bounded<f64> {
    let f: Vec<Frag<f64>> = frags.iter().map(Frag::of).collect();
    let b = tail_blend_t(&f, k, keep, tail);
    Bounded {
        rgba: to_f64(b.rgba),
        ..b
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;
    use crate::composite;
    use rand::Rng;

    const MODES: [(Keep, TailMode); 4] = [
        (Keep::Nearest, TailMode::Drop),
        (Keep::Nearest, TailMode::Blend),
        (Keep::First, TailMode::Drop),
        (Keep::First, TailMode::Blend),
    ];

    #[test]
    fn tail_is_exact_when_depth_complexity_is_at_most_k() {
        let mut rng = rng(41);
        for (keep, mode) in MODES {
            for k in [1usize, 4, 8] {
                for n in 0..=k {
                    let px = pixel(&mut rng, n, 0.05, 0.95, 1.0, 10.0);
                    let b = tail_blend(&arrival(&px), k, keep, mode);
                    assert_eq!((b.dropped, b.tailed), (0, 0));
                    assert!(
                        max_abs(b.rgba, exact(&px)) < 1e-12,
                        "{keep:?} {mode:?} k {k}"
                    );
                }
            }
        }
    }

    #[test]
    fn tail_drop_equals_the_truncated_reference_and_counts_what_it_lost() {
        let mut rng = rng(42);
        for _ in 0..100 {
            let n = rng.random_range(0..40);
            let px = pixel(&mut rng, n, 0.05, 0.95, 1.0, 10.0);
            let b = tail_blend(&arrival(&px), 8, Keep::Nearest, TailMode::Drop);
            // The reference's own k-nearest definition (FragmentLists::composite_first).
            assert!(max_abs(b.rgba, composite(px.iter().take(8))) < 1e-12);
            assert_eq!(b.dropped as usize, n.saturating_sub(8));
            let b = tail_blend(&arrival(&px), 8, Keep::First, TailMode::Blend);
            assert_eq!((b.dropped, b.tailed as usize), (0, n.saturating_sub(8)));
        }
    }

    #[test]
    fn tail_blend_keeps_alpha_exact_and_is_order_independent_for_nearest() {
        let mut rng = rng(43);
        for _ in 0..100 {
            let n = rng.random_range(0..60);
            let px = pixel(&mut rng, n, 0.02, 0.95, 1.0, 10.0);
            let want = exact(&px);
            for keep in [Keep::Nearest, Keep::First] {
                let b = tail_blend(&arrival(&px), 4, keep, TailMode::Blend);
                assert_valid(b.rgba, "tail blend");
                assert!(
                    (b.rgba[3] - want[3]).abs() < 1e-12,
                    "A exact with a blended tail"
                );
            }
            // Nearest-k and the tail's sums ignore arrival order (up to summation rounding).
            let a = tail_blend(&arrival(&px), 4, Keep::Nearest, TailMode::Blend).rgba;
            let d = tail_blend(&px, 4, Keep::Nearest, TailMode::Blend).rgba;
            assert!(max_abs(a, d) < 1e-12);
        }
    }

    #[test]
    fn mean_alpha_opacity_is_at_most_the_exact_one() {
        // (1 − ᾱ)ⁿ ≥ Π(1 − αᵢ) by the AM–GM inequality: Bavoil & Myers underestimate opacity.
        let mut rng = rng(44);
        for _ in 0..200 {
            let n = rng.random_range(1..30);
            let mut s = TailSums::<f64>::default();
            for f in pixel(&mut rng, n, 0.0, 1.0, 1.0, 2.0) {
                s.add(&Frag::of(&f));
            }
            assert!(s.mean_alpha_opacity() <= s.exact_opacity() + 1e-12);
        }
    }
}
