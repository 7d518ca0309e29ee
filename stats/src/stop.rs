//! When to stop sampling one point: nvbench's stopping criterion adapted to GPU passes.
//!
//! After every kept sample, in this order (first match wins):
//! 1. **TargetReached** — at least `min_samples` samples and `min_time_ms` of accumulated
//!    *measured* time (nvbench's `min-time` also sums the GPU times, not wall time), and the
//!    noise is at most `max_noise`. The noise is the relative half-width of the
//!    distribution-free 95 % CI of the median ([`crate::median_ci`]): it needs no assumption
//!    on the distribution (frame times are skewed, with a tail), it is exact in coverage, and
//!    it is recomputed cheaply after every sample. nvbench uses the relative standard deviation,
//!    which converges to the intrinsic noise instead of shrinking with more samples; the CI
//!    answers the question a reader has — how well is the *median* known.
//! 2. **MaxSamples** — `max_samples` samples kept.
//! 3. **MaxTime** — `max_time_ms` of wall time spent on the point (measured by the caller from
//!    the first sample; warm-up excluded). Like nvbench's timeout this ends the point even
//!    before `min_samples`.
//! 4. **NoImprovement** — the series is drifting, so more samples cannot narrow the CI of one
//!    median: checked every `drift_every` samples (nvbench checks its convergence every 16)
//!    once the minimums are met, it fires when the medians of the first and second halves of
//!    the samples (in time order) differ by more than `max_noise` *and* a Mann–Whitney U test
//!    calls the halves different at `drift_alpha` (0.1 %: independent noise trips it about once
//!    in a thousand checks). nvbench instead stops when its noise value has stabilised above the
//!    target; the CI width of independent samples keeps shrinking as 1/√n but fluctuates too
//!    much from sample to sample for a "has not improved lately" test to tell stuck from slow
//!    (tried in simulation: such rules stopped ±50 % white noise early in over half the runs),
//!    whereas a drift is exactly the case where waiting does not help.
//!
//! A point that stops for any reason other than TargetReached is `noisy` (`target_reached =
//! false`). Throttled samples are not pushed: [`Sampler::push_discarded`] counts them and still
//! enforces `max_time_ms`.

use crate::median_ci::rel_half_width;
use crate::mwu::mann_whitney_u;
use crate::summary::median_unsorted;

#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StopRule {
    /// Samples before the target may end the point. 10 = nvbench's default `min-samples`.
    pub min_samples: usize,
    /// Accumulated measured (GPU) time before the target may end the point. 0 by default: one
    /// frame of any pass is far above the timestamp resolution; raise it for µs-scale passes.
    pub min_time_ms: f64,
    /// Target relative half-width of the 95 % CI of the median. 0.5 % = nvbench's default
    /// `max-noise` (there a relative standard deviation, a stricter bar at 10 samples and a
    /// looser one past ~25). A stable GPU pass (≈0.3–1 % spread) meets it in 10–30 samples.
    pub max_noise: f64,
    /// Hard cap on kept samples: 50 keeps a noisy point's cost bounded (5× the minimum).
    pub max_samples: usize,
    /// Hard cap on the wall time of a point's samples (nvbench's `timeout`, 15 s there for µs
    /// kernels; 1 s here so a suite of a few hundred points stays within minutes even when every
    /// point is noisy). Counted from the first sample: warm-up and clock lift are not in it.
    pub max_time_ms: f64,
    /// Samples between drift checks.
    pub drift_every: usize,
    /// Significance of the drift check.
    pub drift_alpha: f64,
}

impl Default for StopRule {
    fn default() -> Self {
        StopRule {
            min_samples: 10,
            min_time_ms: 0.0,
            max_noise: 0.005,
            max_samples: 50,
            max_time_ms: 1000.0,
            drift_every: 16,
            drift_alpha: 0.001,
        }
    }
}

/// A stopping rule that cannot work, naming its settings.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StopRuleError {
    #[error("max_samples must be at least 1")]
    NoSamples,
    #[error("min_samples ({min}) exceeds max_samples ({max})")]
    MinAboveMax { min: usize, max: usize },
    #[error("max_noise must be ≥ 0, got {0}")]
    Noise(f64),
    #[error("need max_time_ms > 0 and min_time_ms ≥ 0, got {max} and {min}")]
    Times { max: f64, min: f64 },
    #[error("need drift_every ≥ 1 and 0 < drift_alpha < 1, got {every} and {alpha}")]
    Drift { every: usize, alpha: f64 },
}

impl StopRule {
    /// Rejects settings that cannot work (a suite file's typo should fail, not run forever).
    pub fn validate(&self) -> Result<(), StopRuleError> {
        if self.max_samples == 0 {
            return Err(StopRuleError::NoSamples);
        }
        if self.min_samples > self.max_samples {
            return Err(StopRuleError::MinAboveMax {
                min: self.min_samples,
                max: self.max_samples,
            });
        }
        if !(self.max_noise >= 0.0 && self.max_noise.is_finite()) {
            return Err(StopRuleError::Noise(self.max_noise));
        }
        if self.max_time_ms.is_nan()
            || self.max_time_ms <= 0.0
            || self.min_time_ms.is_nan()
            || self.min_time_ms < 0.0
        {
            return Err(StopRuleError::Times {
                max: self.max_time_ms,
                min: self.min_time_ms,
            });
        }
        if self.drift_every == 0 || !(self.drift_alpha > 0.0 && self.drift_alpha < 1.0) {
            return Err(StopRuleError::Drift {
                every: self.drift_every,
                alpha: self.drift_alpha,
            });
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    TargetReached,
    MaxSamples,
    MaxTime,
    NoImprovement,
}

impl StopReason {
    pub fn as_str(self) -> &'static str {
        match self {
            StopReason::TargetReached => "target_reached",
            StopReason::MaxSamples => "max_samples",
            StopReason::MaxTime => "max_time",
            StopReason::NoImprovement => "no_improvement",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decision {
    Continue,
    Stop(StopReason),
}

/// The sampling state of one point.
#[derive(Clone, Debug)]
pub struct Sampler {
    rule: StopRule,
    /// Kept samples in the order taken.
    samples: Vec<f64>,
    /// The same, ascending (kept by insertion: O(n) per push).
    sorted: Vec<f64>,
    total_ms: f64,
    elapsed_ms: f64,
    discarded: usize,
    last: Decision,
}

impl Sampler {
    pub fn new(rule: StopRule) -> Sampler {
        Sampler {
            rule,
            samples: Vec::new(),
            sorted: Vec::new(),
            total_ms: 0.0,
            elapsed_ms: 0.0,
            discarded: 0,
            last: Decision::Continue,
        }
    }

    /// Records a kept sample (ms) taken `elapsed_ms` after the point's first sample began, and
    /// says whether to take another. A non-finite sample is a caller bug and panics.
    pub fn push(&mut self, sample_ms: f64, elapsed_ms: f64) -> Decision {
        assert!(sample_ms.is_finite(), "non-finite sample {sample_ms}");
        self.samples.push(sample_ms);
        let at = self.sorted.partition_point(|&x| x < sample_ms);
        self.sorted.insert(at, sample_ms);
        self.total_ms += sample_ms;
        self.elapsed_ms = elapsed_ms;
        self.last = self.decide();
        self.last
    }

    /// Records a discarded (throttled) sample: only the time cap can end the point here.
    pub fn push_discarded(&mut self, elapsed_ms: f64) -> Decision {
        self.discarded += 1;
        self.elapsed_ms = elapsed_ms;
        self.last = if elapsed_ms >= self.rule.max_time_ms {
            Decision::Stop(StopReason::MaxTime)
        } else {
            Decision::Continue
        };
        self.last
    }

    fn decide(&self) -> Decision {
        let r = &self.rule;
        let n = self.samples.len();
        let minimums = n >= r.min_samples && self.total_ms >= r.min_time_ms;
        if minimums && self.noise() <= r.max_noise {
            return Decision::Stop(StopReason::TargetReached);
        }
        if n >= r.max_samples {
            return Decision::Stop(StopReason::MaxSamples);
        }
        if self.elapsed_ms >= r.max_time_ms {
            return Decision::Stop(StopReason::MaxTime);
        }
        if minimums && n.is_multiple_of(r.drift_every) && self.drifting() {
            return Decision::Stop(StopReason::NoImprovement);
        }
        Decision::Continue
    }

    /// First half against second half (time order), as documented in the module.
    fn drifting(&self) -> bool {
        let h = self.samples.len() / 2;
        if h < 2 {
            return false;
        }
        let (a, b) = self.samples.split_at(h);
        let (ma, mb) = (
            median_unsorted(&mut a.to_vec()),
            median_unsorted(&mut b.to_vec()),
        );
        let moved = if ma > 0.0 {
            (mb / ma - 1.0).abs() > self.rule.max_noise
        } else {
            mb != ma
        };
        moved && mann_whitney_u(a, b).is_some_and(|t| t.p < self.rule.drift_alpha)
    }

    /// The current noise: relative half-width of the 95 % CI of the median (∞ below 6).
    pub fn noise(&self) -> f64 {
        rel_half_width(&self.sorted)
    }
    /// Kept samples in the order taken.
    pub fn samples(&self) -> &[f64] {
        &self.samples
    }
    pub fn n(&self) -> usize {
        self.samples.len()
    }
    pub fn discarded(&self) -> usize {
        self.discarded
    }
    pub fn elapsed_ms(&self) -> f64 {
        self.elapsed_ms
    }
    pub fn rule(&self) -> &StopRule {
        &self.rule
    }
    /// Why sampling stopped, `None` while it goes on.
    pub fn reason(&self) -> Option<StopReason> {
        match self.last {
            Decision::Continue => None,
            Decision::Stop(r) => Some(r),
        }
    }
    /// Whether the point met its noise target (`target_reached`; `noisy` when false).
    pub fn target_reached(&self) -> bool {
        self.reason() == Some(StopReason::TargetReached)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// Deterministic pseudo-noise in [−1, 1): splitmix64 of the index, so the series are the
    /// same on every machine and every version of `rand`.
    pub(crate) fn pseudo(i: usize) -> f64 {
        let mut z = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// Pushes `series(i)` with each sample taking `ms_per_sample` of wall time.
    fn run(rule: StopRule, ms_per_sample: f64, series: impl Fn(usize) -> f64) -> Sampler {
        let mut s = Sampler::new(rule);
        for i in 0.. {
            if let Decision::Stop(_) = s.push(series(i), (i + 1) as f64 * ms_per_sample) {
                break;
            }
            assert!(i < 100_000, "never stopped");
        }
        s
    }

    #[test]
    fn stable_series_stops_early_on_target() {
        // 1.0 ± 0.1 %: the CI of the median is far below 0.5 % once it exists.
        let s = run(StopRule::default(), 2.0, |i| 1.0 + 0.001 * pseudo(i));
        assert_eq!(s.reason(), Some(StopReason::TargetReached));
        assert_eq!(s.n(), 10, "stops at min_samples");
        assert!(s.target_reached());
    }

    #[test]
    fn noisy_series_runs_to_max_samples() {
        // 1.0 ± 50 % independent noise: the CI shrinks but not to 0.5 % within 50 samples, and
        // it is not drift.
        let s = run(StopRule::default(), 2.0, |i| 1.0 + 0.5 * pseudo(i));
        assert_eq!(s.reason(), Some(StopReason::MaxSamples));
        assert_eq!(s.n(), 50);
        assert!(!s.target_reached());
    }

    #[test]
    fn independent_noise_rarely_counts_as_drift() {
        // Over 300 seeded ±50 % white-noise series, the drift check (2 checks a series at
        // α = 0.1 %) should essentially never fire: allow 3 (expected ≈ 0.6).
        let mut early = 0;
        for seed in 0..300 {
            let mut rng = Pcg64::seed_from_u64(seed);
            let xs: Vec<f64> = (0..50).map(|_| 1.0 + rng.random_range(-0.5..0.5)).collect();
            let s = run(StopRule::default(), 2.0, |i| xs[i]);
            if s.reason() != Some(StopReason::MaxSamples) {
                early += 1;
            }
        }
        assert!(
            early <= 3,
            "{early} of 300 white-noise series stopped early"
        );
    }

    #[test]
    fn drifting_series_stops_without_improvement() {
        // +1 % per sample with ±0.1 % noise: the halves differ at the first check (16).
        let s = run(StopRule::default(), 2.0, |i| {
            (1.0 + 0.01 * i as f64) * (1.0 + 0.001 * pseudo(i))
        });
        assert_eq!(s.reason(), Some(StopReason::NoImprovement));
        assert_eq!(s.n(), 16);
    }

    #[test]
    fn max_time_is_respected() {
        // 150 ms per sample: the 1 s cap ends a noisy point after 7 samples (1050 ms).
        let s = run(StopRule::default(), 150.0, |i| 1.0 + 0.5 * pseudo(i));
        assert_eq!(s.reason(), Some(StopReason::MaxTime));
        assert_eq!(s.n(), 7);
        assert!(s.elapsed_ms() >= 1000.0 && s.elapsed_ms() < 1150.0);
    }

    #[test]
    fn min_samples_and_min_time_are_respected() {
        // Identical samples reach the target as soon as the minimums allow.
        let rule = StopRule {
            min_samples: 17,
            ..StopRule::default()
        };
        assert_eq!(run(rule, 1.0, |_| 1.0).n(), 17);
        // 40 ms of measured time at 2.5 ms a sample: 16 samples, past min_samples = 10.
        let rule = StopRule {
            min_time_ms: 40.0,
            ..StopRule::default()
        };
        let s = run(rule, 3.0, |_| 2.5);
        assert_eq!((s.n(), s.reason()), (16, Some(StopReason::TargetReached)));
    }

    #[test]
    fn discarded_samples_count_toward_time_only() {
        let mut s = Sampler::new(StopRule::default());
        assert_eq!(s.push_discarded(10.0), Decision::Continue);
        assert_eq!(s.push_discarded(999.0), Decision::Continue);
        assert_eq!(
            s.push_discarded(1000.0),
            Decision::Stop(StopReason::MaxTime)
        );
        assert_eq!((s.n(), s.discarded()), (0, 3));
    }

    #[test]
    fn validate_rejects_impossible_rules() {
        assert!(StopRule::default().validate().is_ok());
        let bad = StopRule {
            min_samples: 60,
            ..StopRule::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("min_samples"));
        let bad = StopRule {
            max_noise: f64::NAN,
            ..StopRule::default()
        };
        assert!(bad.validate().is_err());
    }
}
