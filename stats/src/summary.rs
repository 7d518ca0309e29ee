//! The numbers written for one point's samples.
//!
//! - `median`, `mean`, `min`, `max`;
//! - `p10`, `p90`, `q1`, `q3`: nearest-rank percentiles `s[round((n−1)·p)]` of the sorted
//!   samples — the definition `gpu_ms_rel_noise` has always used, so old and new runs agree;
//! - `p95`, `p99`: the tail, nearest-rank as above (`gpu_ms_p95`, `gpu_ms_p99`; the p50 column
//!   is the median, so it agrees with `gpu_ms_median` on every row);
//! - `rel_noise = (p90 − p10) / median` (kept column);
//! - `median_ci`, `mean_ci`: percentile-bootstrap 95 % CIs (criterion.rs's method): resample the
//!   samples with replacement [`BOOTSTRAP_RESAMPLES`] times from a PCG stream seeded with
//!   `seed`, take each resample's median and mean, and keep the 2.5th and 97.5th percentiles of
//!   those. 2000 resamples put the Monte-Carlo error of a 95 % bound well under the CI's own
//!   width for the 10–100 samples a point takes, and cost ~1 ms.
//! - `rel_ci = (ci_hi − ci_lo) / 2 / median` (`gpu_ms_rel_ci`);
//! - `outliers`: Tukey's fences, samples outside `[q1 − 1.5·IQR, q3 + 1.5·IQR]`;
//! - `rel_stdev`: sample standard deviation / mean (nvbench's "noise"), for reference.

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use crate::median_ci::median_of_sorted;

/// Bootstrap resamples per CI.
pub const BOOTSTRAP_RESAMPLES: usize = 2000;

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Summary {
    pub n: usize,
    pub median: f64,
    pub mean: f64,
    pub min: f64,
    pub max: f64,
    pub p10: f64,
    pub p90: f64,
    pub p95: f64,
    pub p99: f64,
    pub q1: f64,
    pub q3: f64,
    pub rel_noise: f64,
    pub median_ci: (f64, f64),
    pub mean_ci: (f64, f64),
    pub rel_ci: f64,
    pub outliers: usize,
    pub rel_stdev: f64,
}

/// Nearest-rank percentile of an ascending slice.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

/// `a / m`, 0 when both are 0, ∞ for a positive `a` over a non-positive median.
fn rel(a: f64, m: f64) -> f64 {
    if a == 0.0 {
        0.0
    } else if m > 0.0 {
        a / m
    } else {
        f64::INFINITY
    }
}

impl Summary {
    /// The summary of `samples` (any order), `None` when empty. Non-finite samples are a
    /// caller bug (a time is always finite): they panic rather than poison every statistic.
    pub fn of(samples: &[f64], seed: u64) -> Option<Summary> {
        Summary::with_resamples(samples, seed, BOOTSTRAP_RESAMPLES)
    }

    pub fn with_resamples(samples: &[f64], seed: u64, resamples: usize) -> Option<Summary> {
        if samples.is_empty() {
            return None;
        }
        assert!(
            samples.iter().all(|x| x.is_finite()),
            "non-finite sample in {samples:?}"
        );
        let mut s = samples.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        let median = median_of_sorted(&s);
        let mean = s.iter().sum::<f64>() / n as f64;
        let (p10, p90) = (percentile(&s, 0.1), percentile(&s, 0.9));
        let (q1, q3) = (percentile(&s, 0.25), percentile(&s, 0.75));
        let iqr = q3 - q1;
        let outliers = s
            .iter()
            .filter(|&&x| x < q1 - 1.5 * iqr || x > q3 + 1.5 * iqr)
            .count();
        let var = if n > 1 {
            s.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64
        } else {
            0.0
        };
        let (median_ci, mean_ci) = bootstrap(samples, seed, resamples);
        Some(Summary {
            n,
            median,
            mean,
            min: s[0],
            max: s[n - 1],
            p10,
            p90,
            p95: percentile(&s, 0.95),
            p99: percentile(&s, 0.99),
            q1,
            q3,
            rel_noise: rel(p90 - p10, median),
            median_ci,
            mean_ci,
            rel_ci: rel(0.5 * (median_ci.1 - median_ci.0), median),
            outliers,
            rel_stdev: rel(var.sqrt(), mean),
        })
    }
}

/// Percentile-bootstrap 95 % CIs of the median and of the mean, from one set of resamples.
fn bootstrap(samples: &[f64], seed: u64, resamples: usize) -> ((f64, f64), (f64, f64)) {
    let n = samples.len();
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut medians = Vec::with_capacity(resamples);
    let mut means = Vec::with_capacity(resamples);
    let mut buf = vec![0.0; n];
    for _ in 0..resamples.max(1) {
        for b in buf.iter_mut() {
            *b = samples[rng.random_range(0..n)];
        }
        means.push(buf.iter().sum::<f64>() / n as f64);
        medians.push(median_unsorted(&mut buf));
    }
    (
        percentile_interval(&mut medians),
        percentile_interval(&mut means),
    )
}

/// Median by selection (reorders `v`).
pub(crate) fn median_unsorted(v: &mut [f64]) -> f64 {
    let n = v.len();
    let (_, &mut hi, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        hi
    } else {
        // The lower middle is the largest of the left part.
        let lo = v[..n / 2].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lo + hi)
    }
}

/// The 2.5th and 97.5th nearest-rank percentiles of bootstrap statistics (reorders `v`).
pub(crate) fn percentile_interval(v: &mut [f64]) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (percentile(v, 0.025), percentile(v, 0.975))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_answers_on_a_small_series() {
        let s = [5.0, 1.0, 4.0, 2.0, 3.0];
        let m = Summary::of(&s, 1).unwrap();
        assert_eq!(
            (m.n, m.median, m.mean, m.min, m.max),
            (5, 3.0, 3.0, 1.0, 5.0)
        );
        // Nearest rank: p10 = s[round(0.4)] = s[0], p90 = s[round(3.6)] = s[4].
        assert_eq!((m.p10, m.p90), (1.0, 5.0));
        assert!((m.rel_noise - 4.0 / 3.0).abs() < 1e-12);
        assert_eq!(m.outliers, 0);
        // Sample stdev of 1..5 is √2.5.
        assert!((m.rel_stdev - 2.5f64.sqrt() / 3.0).abs() < 1e-12);
        // Bootstrap CIs lie within the data and around the estimates.
        assert!(m.median_ci.0 >= 1.0 && m.median_ci.1 <= 5.0);
        assert!(m.median_ci.0 <= 3.0 && m.median_ci.1 >= 3.0);
        assert!(m.mean_ci.0 < 3.0 && m.mean_ci.1 > 3.0);
        assert!(Summary::of(&[], 1).is_none());
    }

    #[test]
    fn the_tail_is_nearest_rank_on_known_samples() {
        // 1..=100 in reverse: p95 = s[round(94.05)] = s[94] = 95, p99 = s[round(98.01)] = 99.
        let s: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        let m = Summary::of(&s, 1).unwrap();
        assert_eq!((m.median, m.p95, m.p99, m.max), (50.5, 95.0, 99.0, 100.0));
        // One spike in 20 samples: p95 = s[round(18.05)] = s[18] stays at the body, p99 =
        // s[round(18.81)] = s[19] is the spike.
        let mut s = vec![1.0; 19];
        s.push(9.0);
        let m = Summary::of(&s, 1).unwrap();
        assert_eq!((m.median, m.p95, m.p99), (1.0, 1.0, 9.0));
        // A single sample is every percentile.
        let m = Summary::of(&[2.0], 1).unwrap();
        assert_eq!((m.p95, m.p99), (2.0, 2.0));
    }

    #[test]
    fn identical_samples_give_a_zero_width_ci() {
        let m = Summary::of(&[2.5; 12], 7).unwrap();
        assert_eq!(m.median_ci, (2.5, 2.5));
        assert_eq!(m.mean_ci, (2.5, 2.5));
        assert_eq!(
            (m.rel_ci, m.rel_noise, m.rel_stdev, m.outliers),
            (0.0, 0.0, 0.0, 0)
        );
    }

    #[test]
    fn tukey_counts_constructed_outliers() {
        // 20 values in [1.00, 1.19], one far high (3.0) and one far low (0.2): nearest-rank
        // q1 = s[5] = 1.04, q3 = s[16] = 1.15 of the 22 values, IQR 0.11, fences
        // [0.875, 1.315].
        let mut s: Vec<f64> = (0..20).map(|i| 1.0 + 0.01 * i as f64).collect();
        s.push(3.0);
        s.push(0.2);
        let m = Summary::of(&s, 3).unwrap();
        assert_eq!(m.outliers, 2);
        // 1.3 moves the quartiles to 1.05 and 1.16 (upper fence 1.325): inside, not counted.
        s.push(1.3);
        assert_eq!(Summary::of(&s, 3).unwrap().outliers, 2);
    }

    #[test]
    fn deterministic_for_a_seed() {
        let s: Vec<f64> = (0..30).map(|i| ((i * 37) % 11) as f64).collect();
        assert_eq!(Summary::of(&s, 42), Summary::of(&s, 42));
    }

    #[test]
    fn median_ci_covers_the_true_median_in_most_trials() {
        // Exponential(1) samples (skewed, like frame times with a tail): true median ln 2.
        // A 95 % interval should miss in about 5 % of trials; the percentile bootstrap of a
        // median under-covers somewhat for small n, so ≥ 90 % of 200 trials is the bar
        // (a binomial(200, 0.95) count falls below 180 with probability < 0.1 %).
        let truth = std::f64::consts::LN_2;
        let mut rng = Pcg64::seed_from_u64(2024);
        let mut hits = 0;
        let trials = 200;
        for t in 0..trials {
            let s: Vec<f64> = (0..31).map(|_| -(1.0 - rng.random::<f64>()).ln()).collect();
            let m = Summary::of(&s, t).unwrap();
            if m.median_ci.0 <= truth && truth <= m.median_ci.1 {
                hits += 1;
            }
        }
        assert!(hits >= 180, "{hits}/{trials}");
    }

    #[test]
    fn median_by_selection_matches_sorting() {
        let mut rng = Pcg64::seed_from_u64(5);
        for n in 1..40 {
            let mut v: Vec<f64> = (0..n).map(|_| rng.random_range(0..10) as f64).collect();
            let mut s = v.clone();
            s.sort_by(f64::total_cmp);
            assert_eq!(median_unsorted(&mut v), median_of_sorted(&s), "n={n}");
        }
    }
}
