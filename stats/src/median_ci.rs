//! The distribution-free 95 % confidence interval of a median, from order statistics.
//!
//! For `n` independent samples of a continuous distribution, the number `B` of samples below
//! the true median is Binomial(n, ½) whatever the distribution. So `[x(l), x(n−l+1)]` (1-based
//! order statistics) covers the median with probability `1 − 2·P(B ≤ l−1)`; `l` is the largest
//! index keeping that ≥ 95 %. No resampling: cheap enough to recompute after every sample,
//! which is why the stopping rule uses it (the bootstrap CI is computed once, in the summary).
//! Below 6 samples no such interval reaches 95 % (`2·2⁻⁵ = 6.25 %` miss for n = 5): `None`.

/// Two-sided miss probability of the interval: 5 %.
pub const ALPHA: f64 = 0.05;

/// Median of an ascending slice (mean of the two middle values for an even count).
pub fn median_of_sorted(s: &[f64]) -> f64 {
    let n = s.len();
    assert!(n > 0, "median of an empty series");
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// The 1-based lower order-statistic index `l` of the 95 % median CI of `n` samples, or `None`
/// when `n` is too small for any interval to reach 95 %.
pub fn lower_index(n: usize) -> Option<usize> {
    if n == 0 {
        return None;
    }
    // P(B ≤ k) accumulated in log space: 2⁻ⁿ underflows for n > 1074.
    let nf = n as f64;
    let mut ln_pmf = -nf * std::f64::consts::LN_2; // ln P(B = 0)
    let mut cdf = 0.0;
    let mut l = 0;
    for k in 0..n {
        cdf += ln_pmf.exp();
        if cdf > ALPHA / 2.0 {
            break;
        }
        // P(B ≤ k) ≤ α/2, so l = k + 1 keeps the coverage ≥ 1 − α.
        l = k + 1;
        ln_pmf += ((nf - k as f64) / (k as f64 + 1.0)).ln();
    }
    (l >= 1).then_some(l)
}

/// The interval `[x(l), x(n−l+1)]` of an ascending slice, or `None` below 6 samples.
pub fn median_ci_order(sorted: &[f64]) -> Option<(f64, f64)> {
    let n = sorted.len();
    let l = lower_index(n)?;
    Some((sorted[l - 1], sorted[n - l]))
}

/// Half-width of that interval relative to the median: the stopping rule's noise measure.
/// `∞` when there is no interval yet, or a positive width around a zero median; 0 for a
/// zero-width interval.
pub fn rel_half_width(sorted: &[f64]) -> f64 {
    let Some((lo, hi)) = median_ci_order(sorted) else {
        return f64::INFINITY;
    };
    let w = 0.5 * (hi - lo);
    let m = median_of_sorted(sorted);
    if w == 0.0 {
        0.0
    } else if m > 0.0 {
        w / m
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lower_index_matches_binomial_tables() {
        // Known values (e.g. Conover, "Practical Nonparametric Statistics", table A3; or by
        // summing C(n,k)/2^n): n=6 → l=1 (miss 2/64 = 3.1 %), n=10 → l=2 (2·11/1024 = 2.1 %),
        // n=20 → l=6 (2·P(B≤5) = 4.1 %), n=5 → none (2/32 = 6.25 % > 5 %).
        assert_eq!(lower_index(5), None);
        assert_eq!(lower_index(6), Some(1));
        assert_eq!(lower_index(10), Some(2));
        assert_eq!(lower_index(20), Some(6));
        // Large n: close to the normal approximation n/2 − 0.98·√n (1000 → 469.0).
        let l = lower_index(1000).unwrap();
        assert!((468..=470).contains(&l), "{l}");
        // Beyond the f64 range of 2^-n: still finite and sensible.
        let l = lower_index(5000).unwrap();
        assert!((2428..=2432).contains(&l), "{l}");
    }

    #[test]
    fn interval_and_relative_width() {
        let s: Vec<f64> = (1..=10).map(|i| i as f64).collect();
        assert_eq!(median_ci_order(&s), Some((2.0, 9.0)));
        assert_eq!(median_of_sorted(&s), 5.5);
        assert!((rel_half_width(&s) - 3.5 / 5.5).abs() < 1e-12);
        assert_eq!(rel_half_width(&s[..5]), f64::INFINITY);
        assert_eq!(rel_half_width(&[2.0; 8]), 0.0);
        assert_eq!(rel_half_width(&[0.0; 8]), 0.0);
    }
}
