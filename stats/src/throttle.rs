//! Which timed samples to discard because the GPU was throttled — nvbench's rule
//! (`measure_cold.cu`, `--throttle-threshold`, default 75 %): a sample whose SM clock, read
//! right after it, is below 75 % of the reference clock is discarded and not counted. The
//! reference is the device's default SM clock (NVML's default application clock; its maximum
//! SM clock where that is unavailable). Without a clock reading nothing is discarded.
//!
//! Samples above the threshold are kept even if NVML reports a slowdown reason; the point is
//! then flagged `throttled` by the caller (a mild power-cap dip is visible in the mean clock,
//! a deep one is discarded here).

/// Fraction of the reference clock below which a sample is discarded.
pub const THROTTLE_FRACTION: f64 = 0.75;

/// Whether a sample taken at `sample_clock_mhz` is discarded against `reference_mhz`. An
/// unusable reference (≤ 0 or not finite) discards nothing; a non-finite reading neither.
pub fn discard(sample_clock_mhz: f64, reference_mhz: f64) -> bool {
    reference_mhz.is_finite()
        && reference_mhz > 0.0
        && sample_clock_mhz.is_finite()
        && sample_clock_mhz < THROTTLE_FRACTION * reference_mhz
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn below_three_quarters_of_the_reference_is_discarded() {
        // H200: default SM clock 1980 MHz → threshold 1485 MHz.
        assert!(discard(1000.0, 1980.0));
        assert!(discard(1484.9, 1980.0));
        assert!(!discard(1485.0, 1980.0));
        assert!(!discard(1755.0, 1980.0));
        assert!(!discard(2100.0, 1980.0));
    }

    #[test]
    fn unknown_clocks_discard_nothing() {
        assert!(!discard(100.0, 0.0));
        assert!(!discard(100.0, f64::NAN));
        assert!(!discard(f64::NAN, 1980.0));
    }
}
