//! What moves along a camera path (issue 42), measured against the exact truth of every view:
//! pure functions of images (the method's premultiplied RGBA in f32, the truth in f64, one per
//! view) and of per-view numbers. The error of one view against its own truth (RMSE, FLIP) is the
//! judge's (`metrics::image_error`, `mfx_flip`); here is what only a sequence of views has.
//!
//! - **Flicker** between consecutive views t−1, t: the mean over pixels of
//!   max over channels |(I_t − I_{t−1}) − (T_t − T_{t−1})|, the part of the method's
//!   frame-to-frame change that the truth's change does not explain. It is the change of the
//!   error image I − T: an error that moves with the scene does not flicker; one that appears,
//!   vanishes or jumps does. An exact method's error is within its f32 bound b per pixel, so its
//!   flicker is within b_{t−1} + b_t pixel by pixel ([`Step::beyond_bound`] counts pixels past it).
//! - **Popping**: the share of pixels whose error against the truth jumps by more than a stated
//!   ε between consecutive views ([`POP_EPSILON`]): max over channels |(I_t − T_t) − (I_{t−1} −
//!   T_{t−1})| > ε, the pixels of the flicker above ε. An error that changes sign at equal size
//!   (a k-buffer's tail swapping which fragment it averages) is a jump; one that follows the
//!   scene is not.
//! - **At rest** (the same view repeated): the share of pixels whose value differs between two
//!   frames ([`differing_share`]); a method without timing-dependent hazards has 0.
//! - **Along the path**: any per-view number (GPU time, RMSE, FLIP) or per-step number (flicker,
//!   popping) summarised as mean, median, p99 and its worst view ([`over_path`]).
//!
//! The pixel measure is the largest channel's, as the judge's per-pixel error and f32 bound are.

/// ε of popping: 0.01, about 2.5 steps of an 8-bit display channel (a jump one can see on a flat
/// gradient), and far above any f32 bound of a composite here (32 layers: 6e-5), so an exact
/// method never pops.
pub const POP_EPSILON: f64 = 0.01;

/// One view of a path: the method's image, the truth it is judged against, and optionally the
/// f32 bound of each pixel of an exact composite (`judge::exact_bounds`).
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    pub image: &'a [[f32; 4]],
    pub truth: &'a [[f64; 4]],
    /// Per pixel (the image may hold several images one after another: the bound of pixel
    /// `i % bound.len()`).
    pub bound: Option<&'a [f64]>,
}

impl Frame<'_> {
    /// The error of pixel `i` per channel, or None when a channel is not finite.
    fn error(&self, i: usize) -> Option<[f64; 4]> {
        let (g, t) = (self.image[i], self.truth[i]);
        let e: [f64; 4] = std::array::from_fn(|c| g[c] as f64 - t[c]);
        e.iter().all(|x| x.is_finite()).then_some(e)
    }
}

/// What changed from view t−1 to view t.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Step {
    /// Mean over pixels of max channel |(I_t − I_{t−1}) − (T_t − T_{t−1})|.
    pub flicker: f64,
    /// Its largest pixel.
    pub flicker_max: f64,
    /// Pixels whose unexplained change exceeds b_{t−1} + b_t (both frames' f32 bounds); None
    /// without bounds.
    pub beyond_bound: Option<usize>,
    /// Mean over pixels of b_{t−1} + b_t: the flicker an exact method stays within; None without
    /// bounds.
    pub flicker_bound: Option<f64>,
    /// Share of pixels whose error changed by more than ε (in some channel).
    pub popping: f64,
    /// Share of pixels whose value changed at all (any channel; the at-rest measure when the
    /// view is the same).
    pub changed: f64,
    /// Pixels left out of the above: a channel not finite in either frame (counted, never
    /// averaged in).
    pub non_finite: usize,
}

/// Flicker, popping (at `epsilon`) and changed pixels from `prev` to `cur` (equal sizes).
pub fn step(prev: &Frame<'_>, cur: &Frame<'_>, epsilon: f64) -> Step {
    let n = cur.image.len();
    assert!(
        prev.image.len() == n && prev.truth.len() == n && cur.truth.len() == n,
        "frames of one path have one size"
    );
    let (mut sum, mut max, mut pops, mut changed, mut bad) = (0.0, 0.0f64, 0usize, 0usize, 0usize);
    let (mut beyond, mut bound_sum) = (0usize, 0.0);
    let bounds = prev.bound.zip(cur.bound);
    for i in 0..n {
        changed += differs(&prev.image[i], &cur.image[i]) as usize;
        let (Some(a), Some(b)) = (prev.error(i), cur.error(i)) else {
            bad += 1;
            continue;
        };
        let u = (0..4).map(|c| (b[c] - a[c]).abs()).fold(0.0, f64::max);
        sum += u;
        max = max.max(u);
        pops += (u > epsilon) as usize;
        if let Some((bp, bc)) = bounds {
            let b = bp[i % bp.len()] + bc[i % bc.len()];
            bound_sum += b;
            beyond += (u > b) as usize;
        }
    }
    let judged = (n - bad).max(1) as f64;
    Step {
        flicker: sum / judged,
        flicker_max: max,
        beyond_bound: bounds.map(|_| beyond),
        flicker_bound: bounds.map(|_| bound_sum / judged),
        popping: pops as f64 / judged,
        changed: changed as f64 / n.max(1) as f64,
        non_finite: bad,
    }
}

/// The pixels (indices) whose error changed by more than `epsilon` from `prev` to `cur`: where
/// a method pops (for the report's frame strip and for tests that say where).
pub fn popped_pixels(prev: &Frame<'_>, cur: &Frame<'_>, epsilon: f64) -> Vec<usize> {
    (0..cur.image.len())
        .filter(|&i| match (prev.error(i), cur.error(i)) {
            (Some(a), Some(b)) => (0..4).any(|c| (b[c] - a[c]).abs() > epsilon),
            _ => false,
        })
        .collect()
}

/// Whether two pixel values differ (NaN in the same channel of both counts as equal, so a
/// constant NaN is not a change).
fn differs(a: &[f32; 4], b: &[f32; 4]) -> bool {
    (0..4).any(|c| a[c] != b[c] && !(a[c].is_nan() && b[c].is_nan()))
}

/// The share of pixels whose value differs between two frames of one view (at rest).
pub fn differing_share(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    assert_eq!(a.len(), b.len(), "frames of one view have one size");
    a.iter().zip(b).filter(|(x, y)| differs(x, y)).count() as f64 / a.len().max(1) as f64
}

/// A number along a path: one value per view (or per step between views).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OverPath {
    pub mean: f64,
    pub median: f64,
    /// Nearest-rank 99th percentile over the views (with fewer than 100 views, the worst or
    /// next to it).
    pub p99: f64,
    /// The largest value and its view (the first of equals).
    pub worst: f64,
    pub worst_view: usize,
    /// Values summarised (non-finite ones are left out and not counted).
    pub count: usize,
}

/// Mean, median, p99 and the worst view of `values` (index = view); None when none is finite.
pub fn over_path(values: &[f64]) -> Option<OverPath> {
    let finite: Vec<(usize, f64)> = values
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .collect();
    let (worst_view, worst) =
        finite
            .iter()
            .copied()
            .fold(None, |best: Option<(usize, f64)>, (i, v)| match best {
                Some((_, b)) if b >= v => best,
                _ => Some((i, v)),
            })?;
    let mut sorted: Vec<f64> = finite.iter().map(|(_, v)| *v).collect();
    sorted.sort_by(f64::total_cmp);
    Some(OverPath {
        mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
        median: mfx_stats::median_of_sorted(&sorted),
        p99: mfx_stats::summary::percentile(&sorted, 0.99),
        worst,
        worst_view,
        count: sorted.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame<'a>(image: &'a [[f32; 4]], truth: &'a [[f64; 4]]) -> Frame<'a> {
        Frame {
            image,
            truth,
            bound: None,
        }
    }

    fn rounded(truth: &[[f64; 4]]) -> Vec<[f32; 4]> {
        truth.iter().map(|p| p.map(|c| c as f32)).collect()
    }

    #[test]
    fn the_truth_rounded_to_f32_flickers_only_within_its_bound_and_never_pops() {
        let t0: Vec<[f64; 4]> = (0..64)
            .map(|i| [0.1 * (i % 7) as f64 / 3.0, 0.3, 0.7, 0.5])
            .collect();
        let t1: Vec<[f64; 4]> = t0
            .iter()
            .map(|p| [p[0] * 0.9 + 0.01, p[1], p[2] / 3.0, 0.6])
            .collect();
        let (i0, i1) = (rounded(&t0), rounded(&t1));
        // f32 rounding: half an ulp of values below 1, 2⁻²⁵, per frame.
        let b = vec![2f64.powi(-25); 64];
        let s = step(
            &Frame {
                bound: Some(&b),
                ..frame(&i0, &t0)
            },
            &Frame {
                bound: Some(&b),
                ..frame(&i1, &t1)
            },
            POP_EPSILON,
        );
        assert!(
            s.flicker > 0.0 && s.flicker <= s.flicker_bound.unwrap(),
            "{s:?}"
        );
        assert_eq!(s.beyond_bound, Some(0));
        assert_eq!(s.popping, 0.0);
        assert!(s.changed > 0.5, "the image moved with the truth: {s:?}");
    }

    #[test]
    fn an_error_that_moves_with_the_scene_does_not_flicker_one_that_appears_does() {
        let t0 = vec![[0.5f64, 0.5, 0.5, 0.5]; 4];
        let t1 = vec![[0.25f64, 0.5, 0.75, 0.5]; 4];
        // The same error (+0.125 in red) in both views: the change is the truth's.
        let off = |t: &[[f64; 4]]| -> Vec<[f32; 4]> {
            t.iter()
                .map(|p| [(p[0] + 0.125) as f32, p[1] as f32, p[2] as f32, p[3] as f32])
                .collect()
        };
        let s = step(&frame(&off(&t0), &t0), &frame(&off(&t1), &t1), POP_EPSILON);
        assert_eq!((s.flicker, s.popping), (0.0, 0.0));
        // A method that stays still while the truth moves: all of the truth's change is its.
        let still = rounded(&t0);
        let s = step(&frame(&still, &t0), &frame(&still, &t1), POP_EPSILON);
        assert_eq!(s.flicker, 0.25);
        assert_eq!(s.flicker_max, 0.25);
        assert_eq!(s.popping, 1.0);
        assert_eq!(s.changed, 0.0);
    }

    #[test]
    fn popping_counts_the_pixels_whose_error_jumps_by_more_than_epsilon_and_says_which() {
        let t = vec![[0.5f64; 4]; 8];
        let a = rounded(&t);
        let mut b = a.clone();
        b[2][1] += 0.02; // jumps by 0.02 > ε
        b[5][3] -= 0.005; // 0.005 ≤ ε: a change, not a pop
        let (fa, fb) = (frame(&a, &t), frame(&b, &t));
        let s = step(&fa, &fb, POP_EPSILON);
        assert_eq!(s.popping, 1.0 / 8.0);
        assert_eq!(popped_pixels(&fa, &fb, POP_EPSILON), vec![2]);
        assert_eq!(s.changed, 2.0 / 8.0);
        // 0.52 and 0.495 in f32: their errors are 0.02 and 0.005 to about 1e-8.
        assert!((s.flicker - 0.025 / 8.0).abs() < 1e-8, "{s:?}");
    }

    #[test]
    fn an_error_that_changes_sign_at_equal_size_pops() {
        let t = vec![[0.5f64; 4]; 2];
        let a: Vec<[f32; 4]> = vec![[0.53, 0.5, 0.5, 0.5]; 2];
        let b: Vec<[f32; 4]> = vec![[0.47, 0.5, 0.5, 0.5], [0.53, 0.5, 0.5, 0.5]];
        let s = step(&frame(&a, &t), &frame(&b, &t), POP_EPSILON);
        assert_eq!(s.popping, 0.5);
        assert_eq!(
            popped_pixels(&frame(&a, &t), &frame(&b, &t), POP_EPSILON),
            vec![0]
        );
    }

    #[test]
    fn non_finite_pixels_are_counted_apart_not_averaged() {
        let t = vec![[0.5f64; 4]; 4];
        let a = rounded(&t);
        let mut b = a.clone();
        b[0][0] = f32::NAN;
        let s = step(&frame(&a, &t), &frame(&b, &t), POP_EPSILON);
        assert_eq!(s.non_finite, 1);
        assert_eq!(s.flicker, 0.0);
        assert_eq!(s.changed, 0.25);
        // A NaN that stays is no change.
        assert_eq!(differing_share(&b, &b), 0.0);
    }

    #[test]
    fn at_rest_differences_are_the_share_of_pixels_that_changed() {
        let a = vec![[0.1f32, 0.2, 0.3, 0.4]; 10];
        let mut b = a.clone();
        b[3][2] = 0.31;
        b[7][0] = 0.1 + f32::EPSILON;
        assert_eq!(differing_share(&a, &a), 0.0);
        assert_eq!(differing_share(&a, &b), 0.2);
    }

    #[test]
    fn a_path_summary_names_its_worst_view() {
        let ms = [1.0, 3.0, 2.0, 3.0, f64::NAN];
        let o = over_path(&ms).unwrap();
        assert_eq!((o.worst, o.worst_view, o.count), (3.0, 1, 4));
        assert_eq!(o.median, 2.5);
        assert_eq!(o.mean, 2.25);
        assert_eq!(o.p99, 3.0);
        assert!(over_path(&[f64::NAN]).is_none());
        // 100 views 1..=100 ms: p99 is the 99th, one below the worst.
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        let o = over_path(&v).unwrap();
        assert_eq!((o.p99, o.worst, o.worst_view), (99.0, 100.0, 99));
    }
}
