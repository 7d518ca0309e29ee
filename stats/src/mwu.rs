//! The Mann–Whitney U test (Wilcoxon rank-sum), two-sided, following scipy.stats.mannwhitneyu
//! (≥ 1.7) exactly, so its p-values can be checked against scipy's:
//!
//! - ranks over both samples with ties averaged; `U1 = R1 − n1(n1+1)/2`, `U2 = n1·n2 − U1`;
//! - `auto` uses the **exact** null distribution when there are no ties and either sample has at
//!   most 8 values, the **normal approximation** otherwise (scipy's `_mwu_choose_method`);
//! - exact: `p = 2·P(U ≥ max(U1, U2))` under H0, from the count of rank arrangements
//!   (the Gaussian binomial coefficient, computed in exact integers);
//! - asymptotic: `z = (max(U1,U2) − n1·n2/2 − ½) / σ` with the tie-corrected
//!   `σ² = n1·n2/12 · ((n+1) − Σ(t³−t)/(n(n−1)))` and continuity correction ½, `p = 2·Φ(−z)`;
//! - p is clipped to [0, 1]. When every value is tied (σ = 0) there is no evidence of a
//!   difference: p = 1 (scipy returns NaN there).
//!
//! Google benchmark's `compare.py` uses this test (`scipy.stats.mannwhitneyu`) to tell whether
//! two sets of repetitions differ.

/// How the p-value was computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum MwuMethod {
    Exact,
    Asymptotic,
}

#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct MwuResult {
    /// U of the first sample (scipy's `statistic`).
    pub u1: f64,
    /// Two-sided p-value.
    pub p: f64,
    pub method: MwuMethod,
}

/// The two-sided test with scipy's automatic method choice. `None` when a sample is empty.
pub fn mann_whitney_u(a: &[f64], b: &[f64]) -> Option<MwuResult> {
    let (u1, ties) = u_statistic(a, b)?;
    let method = if (a.len() > 8 && b.len() > 8) || ties.iter().any(|&t| t > 1) {
        MwuMethod::Asymptotic
    } else {
        MwuMethod::Exact
    };
    Some(finish(a.len(), b.len(), u1, &ties, method))
}

/// The test with a chosen method (exact ignores ties, as scipy's `method='exact'` does).
pub fn mann_whitney_u_with(a: &[f64], b: &[f64], method: MwuMethod) -> Option<MwuResult> {
    let (u1, ties) = u_statistic(a, b)?;
    Some(finish(a.len(), b.len(), u1, &ties, method))
}

fn finish(n1: usize, n2: usize, u1: f64, ties: &[usize], method: MwuMethod) -> MwuResult {
    let u2 = (n1 * n2) as f64 - u1;
    let u = u1.max(u2);
    let p = match method {
        MwuMethod::Exact => 2.0 * exact_sf(n1, n2, u),
        MwuMethod::Asymptotic => {
            let (n1f, n2f) = (n1 as f64, n2 as f64);
            let n = n1f + n2f;
            let tie_term: f64 = ties.iter().map(|&t| (t as f64).powi(3) - t as f64).sum();
            let var = n1f * n2f / 12.0 * ((n + 1.0) - tie_term / (n * (n - 1.0)));
            if var <= 0.0 {
                1.0
            } else {
                let z = (u - n1f * n2f / 2.0 - 0.5) / var.sqrt();
                2.0 * normal_sf(z)
            }
        }
    };
    MwuResult {
        u1,
        p: p.clamp(0.0, 1.0),
        method,
    }
}

/// U1 and the sizes of the tie groups of the pooled samples.
fn u_statistic(a: &[f64], b: &[f64]) -> Option<(f64, Vec<usize>)> {
    if a.is_empty() || b.is_empty() {
        return None;
    }
    let mut all: Vec<(f64, bool)> = a
        .iter()
        .map(|&x| (x, true))
        .chain(b.iter().map(|&x| (x, false)))
        .collect();
    all.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut r1 = 0.0;
    let mut ties = Vec::new();
    let mut i = 0;
    while i < all.len() {
        let mut j = i + 1;
        while j < all.len() && all[j].0 == all[i].0 {
            j += 1;
        }
        // 1-based ranks i+1..=j share their average.
        let avg = (i + 1 + j) as f64 / 2.0;
        r1 += avg * all[i..j].iter().filter(|x| x.1).count() as f64;
        ties.push(j - i);
        i = j;
    }
    let n1 = a.len() as f64;
    Some((r1 - n1 * (n1 + 1.0) / 2.0, ties))
}

/// P(U ≥ u) under H0 for sizes n1, n2 without ties. The number of arrangements with U = k is
/// the coefficient of q^k in the Gaussian binomial [n1+n2 choose n1]_q, built as
/// Π_{i=1..m} (1 − q^{n+i}) / (1 − q^i) with m = min(n1, n2), n = max(n1, n2); each partial
/// product is itself a Gaussian binomial, so every coefficient stays an exact integer (i128:
/// C(n1+n2, n1) < 2^127 up to n1 = n2 = 64; beyond that the asymptotic test is used).
fn exact_sf(n1: usize, n2: usize, u: f64) -> f64 {
    let (m, n) = (n1.min(n2), n1.max(n2));
    if m + n > 128 {
        // Too large for exact counts (and scipy would not ask): the normal approximation.
        return finish(n1, n2, u, &[], MwuMethod::Asymptotic).p / 2.0;
    }
    let len = m * n + 1;
    let mut c = vec![0i128; len];
    c[0] = 1;
    for i in 1..=m {
        // × (1 − q^{n+i}), descending so each term uses the old coefficient.
        let s = n + i;
        for k in (s..len).rev() {
            c[k] -= c[k - s];
        }
        // ÷ (1 − q^i): a running sum with stride i.
        for k in i..len {
            c[k] += c[k - i];
        }
    }
    let total: i128 = c.iter().sum();
    let from = u.ceil().max(0.0) as usize;
    let tail: i128 = c.iter().skip(from).sum();
    tail as f64 / total as f64
}

/// Φ(−z) = P(Z > z) for a standard normal Z, via erfc (accurate in the far tail).
pub fn normal_sf(z: f64) -> f64 {
    0.5 * libm::erfc(z / std::f64::consts::SQRT_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values printed by scipy 1.17.1 (`pip install scipy` in a venv):
    /// `scipy.stats.mannwhitneyu(a, b)` (method 'auto') with the arrays of each case, and
    /// `mannwhitneyu(a, b, method='exact')` for the exact one on large samples.
    fn close(got: f64, want: f64) {
        assert!(
            (got - want).abs() <= 1e-12_f64.max(want.abs() * 1e-9),
            "got {got:e}, want {want:e}"
        );
    }

    #[test]
    fn exact_small_samples_match_scipy() {
        // method='auto' → exact (no ties, n ≤ 8).
        let r = mann_whitney_u(&[1.1, 2.2, 3.3, 4.4, 5.5], &[6.6, 7.7, 8.8, 9.9, 10.5]).unwrap();
        assert_eq!(r.method, MwuMethod::Exact);
        assert_eq!(r.u1, 0.0);
        close(r.p, 0.007936507936507936);
        let r = mann_whitney_u(&[1.0, 4.0, 2.0, 7.0], &[3.0, 5.0, 6.0, 8.0, 9.0]).unwrap();
        assert_eq!(r.u1, 4.0);
        close(r.p, 0.19047619047619047);
        let r = mann_whitney_u(&[3.0, 1.0, 5.0], &[2.0, 4.0, 6.0]).unwrap();
        assert_eq!(r.u1, 3.0);
        close(r.p, 0.7);
        // U = n1·n2/2: p clipped to 1.
        let r = mann_whitney_u(&[1.0, 4.0], &[2.0, 3.0]).unwrap();
        close(r.p, 1.0);
    }

    #[test]
    fn asymptotic_matches_scipy_with_ties_and_large_samples() {
        // Ties → asymptotic with tie correction.
        let r =
            mann_whitney_u(&[1.0, 2.0, 2.0, 3.0, 4.0], &[2.0, 3.0, 3.0, 5.0, 6.0, 7.0]).unwrap();
        assert_eq!(r.method, MwuMethod::Asymptotic);
        assert_eq!(r.u1, 6.0);
        close(r.p, 0.11390314458853068);
        // n1, n2 > 8 → asymptotic.
        let a: Vec<f64> = (0..12).map(|i| i as f64 * 0.7).collect();
        let b: Vec<f64> = (0..10).map(|i| 3.0 + i as f64 * 0.9).collect();
        let r = mann_whitney_u(&a, &b).unwrap();
        assert_eq!(r.method, MwuMethod::Asymptotic);
        assert_eq!(r.u1, 24.0);
        close(r.p, 0.019242436939707945);
        // The exact distribution on the same samples.
        let r = mann_whitney_u_with(&a, &b, MwuMethod::Exact).unwrap();
        close(r.p, 0.01689950915957108);
    }

    #[test]
    fn all_tied_is_no_evidence() {
        let r = mann_whitney_u(&[1.0; 6], &[1.0; 7]).unwrap();
        assert_eq!(r.p, 1.0);
        assert!(mann_whitney_u(&[], &[1.0]).is_none());
    }

    #[test]
    fn exact_counts_sum_to_binomial() {
        // P(U ≥ 0) = 1 and the distribution is symmetric: P(U ≥ mn/2 + d) = P(U ≤ mn/2 − d).
        assert!((exact_sf(7, 9, 0.0) - 1.0).abs() < 1e-15);
        let (m, n) = (7usize, 9usize);
        for u in 0..=(m * n) {
            let upper = exact_sf(m, n, u as f64);
            let lower = 1.0 - exact_sf(m, n, (m * n - u + 1) as f64);
            assert!((upper - lower).abs() < 1e-12, "u={u}");
        }
    }
}
