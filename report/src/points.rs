//! Chart points made from rows (the step between the data and the charts).

use schema::cols;

use crate::charts::Pt;
use crate::data::{Rec, Runs};

/// A GPU-time point: y = median, whisker = the 95 % CI of the median when the CSV has one.
pub fn time_pt(r: &Rec, x: f64) -> Option<Pt> {
    let (lo, hi) = r.gpu_ci().unzip();
    Some(Pt::spread(x, r.f(cols::GPU_MS_MEDIAN)?, lo, hi).flagged(r.flagged()))
}

/// What the time whiskers of a run's charts mean, for captions.
pub fn ci_caption(runs: &Runs) -> &'static str {
    if runs.has(cols::GPU_MS_CI_LO) {
        "Whiskers: 95 % bootstrap CI of the median GPU time."
    } else {
        "No whiskers: this CSV has no confidence interval of the median (gpu_ms_ci_lo/hi), and min–max is not one."
    }
}

/// `ci_caption` for a set of rows (whether any has a CI).
pub fn ci_caption_rows(rows: &[&Rec]) -> &'static str {
    if rows.iter().any(|r| r.gpu_ci().is_some()) {
        "Whiskers: 95 % bootstrap CI of the median GPU time."
    } else {
        "No whiskers: these rows have no confidence interval of the median (gpu_ms_ci_lo/hi), and min–max is not one."
    }
}
