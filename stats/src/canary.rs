//! Which timed samples to discard because the GPU as a whole ran slow: a fixed "canary" kernel is
//! timed right after every sample, and a sample whose canary took more than `max_ratio` times the
//! fastest canary seen so far in the process is discarded (not counted; the stopping rule goes
//! on). Measured on the H200: whole points ran 1.4–2.3× slower in one of two identical runs —
//! every pass of them, the trivial ones included — while NVML read 1980 MHz and no throttle
//! reason, so the clock rule ([`crate::throttle`]) cannot see it. The canary measures the state
//! the clocks do not report; a slowdown it does not see belongs to the point's own buffers.

/// Default `[timing] canary_max_ratio`: far above the canary's own jitter (a few %), far below
/// the 1.4–2.3× slow states seen.
pub const CANARY_MAX_RATIO: f64 = 1.15;

/// How many of the fastest canaries the baseline keeps: the baseline is the slowest of them, so
/// up to `KEEP − 1` freak fast readings (a timestamp glitch) cannot make every later sample slow.
pub const CANARY_KEEP: usize = 5;

/// The fastest canaries of the process: ratios are taken against the slowest of the
/// [`CANARY_KEEP`] fastest (against the slowest of all, while there are fewer).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CanaryBaseline {
    fastest: Vec<f64>,
}

impl CanaryBaseline {
    /// Feeds one canary time; returns its ratio to the baseline after it is counted (so the
    /// first is 1). Non-finite or non-positive times give `None` and change nothing.
    pub fn push(&mut self, ms: f64) -> Option<f64> {
        if !(ms.is_finite() && ms > 0.0) {
            return None;
        }
        let at = self.fastest.partition_point(|&f| f <= ms);
        if at < CANARY_KEEP {
            self.fastest.insert(at, ms);
            self.fastest.truncate(CANARY_KEEP);
        }
        self.baseline_ms().map(|b| ms / b)
    }

    /// The time ratios are taken against.
    pub fn baseline_ms(&self) -> Option<f64> {
        self.fastest.last().copied()
    }
}

/// Whether a sample whose canary ratio is `ratio` is discarded (`max_ratio` ≤ 1: never).
pub fn canary_discard(ratio: Option<f64>, max_ratio: f64) -> bool {
    match ratio {
        Some(r) => max_ratio > 1.0 && r > max_ratio,
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratios_are_against_the_fifth_fastest_so_far() {
        let mut b = CanaryBaseline::default();
        assert_eq!(b.push(0.040), Some(1.0));
        // Fewer than five: the slowest of them is the baseline.
        assert!((b.push(0.080).unwrap() - 1.0).abs() < 1e-12);
        for _ in 0..3 {
            b.push(0.040);
        }
        // Five kept: 0.040 ×4, 0.080 → 0.080 drops out once a sixth fast one arrives.
        assert_eq!(b.baseline_ms(), Some(0.080));
        b.push(0.041);
        assert_eq!(b.baseline_ms(), Some(0.041));
        assert!((b.push(0.082).unwrap() - 2.0).abs() < 1e-12);
        // One freak fast reading does not move the baseline far.
        b.push(1e-6);
        assert_eq!(b.baseline_ms(), Some(0.040));
        assert_eq!(b.push(f64::NAN), None);
        assert_eq!(b.push(0.0), None);
        assert_eq!(b.baseline_ms(), Some(0.040));
    }

    #[test]
    fn a_slow_state_is_discarded_and_jitter_is_not() {
        // The H200's slow points: 1.45× (the floors of shells(4,16) at 1024²), 2.2× (scan and
        // transform passes of compute_abuffer points). Jitter: a few %.
        assert!(canary_discard(Some(1.45), CANARY_MAX_RATIO));
        assert!(canary_discard(Some(2.2), CANARY_MAX_RATIO));
        assert!(!canary_discard(Some(1.03), CANARY_MAX_RATIO));
        assert!(!canary_discard(Some(1.15), CANARY_MAX_RATIO));
        assert!(!canary_discard(None, CANARY_MAX_RATIO));
        // 0 turns the rule off.
        assert!(!canary_discard(Some(5.0), 0.0));
    }
}
