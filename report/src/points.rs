//! Chart points made from rows (the step between the data and the charts).

use schema::cols;

use crate::charts::Pt;
use mfx_analysis::data::{Interval, Rec};

/// A GPU-time point: y = median, whisker = its interval (a 95 % CI, or min–max where too few
/// samples for one). `None` when the row's time is not trusted (its timestamps missed part of
/// the frame): such rows are never drawn as times.
pub fn time_pt(r: &Rec, x: f64) -> Option<Pt> {
    let (lo, hi) = r.gpu_ci().unzip();
    Some(Pt::spread(x, r.trusted_ms()?, lo, hi).flagged(r.flagged()))
}

/// What the time whiskers of a chart's rows mean, for its caption (never the whole run's: a
/// caption describes its own chart).
pub fn ci_caption_rows(rows: &[&Rec]) -> String {
    if rows.iter().any(|r| r.gpu_ci().is_some()) {
        whiskers(rows)
    } else {
        "No whiskers: these rows have no confidence interval of the median (gpu_ms_ci_lo/hi), and min–max is not one.".into()
    }
}

/// Names the whiskers honestly: a 95 % interval only where the rows have enough samples for one;
/// untrusted times are said to be left out.
fn whiskers(rows: &[&Rec]) -> String {
    let timed: Vec<&&Rec> = rows.iter().filter(|r| r.gpu_ci().is_some()).collect();
    let ranges: Vec<Interval> = timed
        .iter()
        .map(|r| r.interval())
        .filter(|i| *i != Interval::Ci95)
        .collect();
    let mut s = if ranges.is_empty() {
        "Whiskers: 95 % CI of the median GPU time.".to_string()
    } else if ranges.len() == timed.len() {
        let ns: std::collections::BTreeSet<String> = ranges.iter().map(|i| i.name()).collect();
        format!(
            "Whiskers: {} of the samples, not a 95 % CI (too few samples for one).",
            ns.into_iter().collect::<Vec<_>>().join(", ")
        )
    } else {
        format!(
            "Whiskers: 95 % CI of the median GPU time, except {} point(s) with too few samples, whose whiskers are the min–max range.",
            ranges.len()
        )
    };
    let untrusted = rows
        .iter()
        .filter(|r| r.ok() && r.f(cols::GPU_MS_MEDIAN).is_some() && !r.time_trusted())
        .count();
    if untrusted > 0 {
        s.push_str(&format!(
            " {untrusted} point(s) whose GPU timestamps miss part of the frame (gpu_time_trusted false) are left out of time charts."
        ));
    }
    s
}

/// A row's p99 GPU time above this multiple of its median is a tail: the summary names it and
/// the tail chart draws the line.
pub const TAIL_RATIO: f64 = 1.2;

/// The fewest kept samples a p95/p99 is shown with: with fewer, nearest-rank p95 is one of the
/// two largest samples and p99 the largest (results/README.md), a maximum, not a tail.
pub const TAIL_MIN_SAMPLES: usize = 20;
