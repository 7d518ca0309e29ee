//! A/A calibration on committed H200 runs (`results/reference/2026-12-02-h200-sessions`: four
//! `methods` runs with three sessions, two device calls of two back-to-back runs each).
//! Leave-one-pair-out: bands measured on one call's pair must keep the other call's pairs
//! ≥ 95 % SAME with no FASTER / SLOWER, and a synthetic ×1.05 copy must still come out SLOWER at
//! ≥ 95 % of points. Fewer bootstrap resamples than `mfx compare` (400, not 2000) keep it fast.

use std::path::PathBuf;

use mfx_analysis::ab::{compare_runs, AbOptions, AbReport};
use mfx_analysis::calibrate::{calibrate, Calibration};
use mfx_stats::Verdict;

fn run(name: &str) -> PathBuf {
    let call = if name == "s3a" || name == "s3b" {
        "call1"
    } else {
        "call2"
    };
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../results/reference/2026-12-02-h200-sessions")
        .join(call)
        .join(format!("methods-{name}"))
}

fn opts(cal: Option<&Calibration>, scale: f64) -> AbOptions {
    let mut o = AbOptions::default();
    o.verdict.resamples = 400;
    o.calibration = cal.cloned();
    o.scale_new = scale;
    o
}

fn count(r: &AbReport, v: Verdict) -> usize {
    r.points.iter().filter(|p| p.time.verdict == v).count()
}

fn frac(r: &AbReport, v: Verdict) -> f64 {
    count(r, v) as f64 / r.points.len() as f64
}

#[test]
fn bands_from_one_call_keep_the_other_calls_pairs_same_and_catch_a_five_percent_change() {
    let cal = calibrate(&[run("s3c"), run("s3d")], &opts(None, 1.0), 1.0).unwrap();
    assert_eq!(cal.points.len(), 220);
    // Some points moved more than the 2 % floor between s3c and s3d (the compute A-buffer's
    // quads(32): two frame-time modes), most did not.
    let wide = cal.points.values().filter(|b| **b > 0.02).count();
    assert!(
        (1..=22).contains(&wide),
        "{wide} points wider than the floor"
    );
    for (a, b) in [("s3a", "s3b"), ("s3a", "s3c"), ("s3b", "s3d")] {
        let r = compare_runs(&run(a), &run(b), &opts(Some(&cal), 1.0)).unwrap();
        assert_eq!(r.points.len(), 220);
        let (f, s) = (count(&r, Verdict::Faster), count(&r, Verdict::Slower));
        assert_eq!((f, s), (0, 0), "{a} → {b}: A/A false alarms");
        assert!(
            frac(&r, Verdict::Same) >= 0.95,
            "{a} → {b}: SAME {}",
            count(&r, Verdict::Same)
        );
        // The same pair with every NEW time ×1.05.
        let r5 = compare_runs(&run(a), &run(b), &opts(Some(&cal), 1.05)).unwrap();
        assert_eq!(count(&r5, Verdict::Faster), 0, "{a} → {b} ×1.05");
        assert!(
            frac(&r5, Verdict::Slower) >= 0.95,
            "{a} → {b} ×1.05: SLOWER {} of {}: {:#?}",
            count(&r5, Verdict::Slower),
            r5.points.len(),
            r5.points
                .iter()
                .filter(|p| p.time.verdict != Verdict::Slower)
                .map(|p| format!(
                    "{} {} {:.3} {:?} {}",
                    p.key, p.time.verdict, p.time.ratio, p.time.ratio_ci, p.time.why
                ))
                .collect::<Vec<_>>()
        );
    }
}

#[test]
fn a_bimodal_point_gets_no_confident_verdict_even_at_the_fixed_band() {
    // s3c's three sessions of the compute A-buffer, quads(32) 1024², small_max = 32, sat in the
    // fast mode (1.62 ms), s3d's in both (1.70): 5 % apart, what the fresh machine
    // called SLOWER (1.061). Whatever the band, that point is not FASTER / SLOWER.
    let key = "methods|quads(depth_complexity=32)|1024x1024|compute_abuffer|small_max=32";
    let r = compare_runs(&run("s3c"), &run("s3d"), &opts(None, 1.0)).unwrap();
    let p = r.points.iter().find(|p| p.key == key).unwrap();
    assert!(p.new_median_ms / p.base_median_ms > 1.03, "{:?}", p.time);
    assert!(p.base_modes.or(p.new_modes).is_some(), "two modes seen");
    // Both runs show both modes: compared mode with mode, the build matches itself.
    assert_eq!(p.time.verdict, Verdict::Same, "{:?}", p.time);
    assert!(p.time.why.contains("mode-matched"), "{}", p.time.why);
    // And no point of any pair of the four runs is FASTER / SLOWER at the fixed 2 % band.
    let names = ["s3a", "s3b", "s3c", "s3d"];
    for (i, a) in names.iter().enumerate() {
        for b in &names[i + 1..] {
            let r = compare_runs(&run(a), &run(b), &opts(None, 1.0)).unwrap();
            let bad: Vec<_> = r
                .points
                .iter()
                .filter(|p| matches!(p.time.verdict, Verdict::Faster | Verdict::Slower))
                .map(|p| format!("{} {:.3}", p.key, p.time.ratio))
                .collect();
            assert!(bad.is_empty(), "{a} → {b}: {bad:?}");
        }
    }
}
