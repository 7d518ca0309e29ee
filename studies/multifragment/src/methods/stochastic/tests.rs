//! Stochastic transparency on lavapipe (4× MSAA) against the 4-sample multisampled truth.

use scenarios::ParamValue::{Bool, Float, Int};
use scenarios::Scene;

use super::*;
use crate::testing::{params, run_truth, scene};

fn run(
    s: &Scene,
    samples: i64,
    passes: i64,
    correction: bool,
    seed: i64,
) -> (Vec<[f32; 4]>, Vec<[f64; 4]>) {
    let p = params(&[
        ("st_samples", Int(samples)),
        ("st_passes", Int(passes)),
        ("st_correction", Bool(correction)),
        ("st_seed", Int(seed)),
    ]);
    let (cap, truth) = run_truth(&Stochastic, s, 32, 32, &p);
    assert_eq!(cap.aa, Some(AaMode::Msaa(samples as u32)));
    (cap.image.unwrap(), truth)
}

fn rmse(img: &[[f32; 4]], truth: &[[f64; 4]]) -> f64 {
    let n = img.len() as f64 * 4.0;
    (img.iter()
        .zip(truth)
        .flat_map(|(a, b)| (0..4).map(move |c| (a[c] as f64 - b[c]).powi(2)))
        .sum::<f64>()
        / n)
        .sqrt()
}

#[test]
fn error_falls_as_samples_grow_4_16_64_on_a_fixed_seed() {
    // 4 samples × 1, 4, 16 passes. Independent passes average: the noise falls as 1/√N, so each
    // ×4 step should halve the RMSE; asserted: by at least a quarter (a wide margin for one seed).
    let s = scene("quads", &[("depth_complexity", Int(6))]);
    for correction in [false, true] {
        let e: Vec<f64> = [1, 4, 16]
            .iter()
            .map(|&p| {
                let (img, truth) = run(&s, 4, p, correction, 7);
                rmse(&img, &truth)
            })
            .collect();
        assert!(e[0] > 0.01, "one pass is noisy ({e:?})");
        assert!(
            e[1] < 0.75 * e[0] && e[2] < 0.75 * e[1],
            "correction {correction}: RMSE over 4, 16, 64 samples {e:?}"
        );
    }
}

#[test]
fn uncorrected_is_unbiased_within_its_measured_spread_on_a_uniform_alpha_scene() {
    // Every quad α = 0.4, distinct colours; 32 seeds of one 4-sample pass. Per seed, the mean
    // over pixels of (estimate − truth) per channel; their mean must lie within 4 standard
    // errors of 0 (|z| > 4 has probability 6e-5 for an unbiased estimator), while the per-seed
    // spread is large (it is noise, not bias, that the test rules on).
    let s = scene(
        "quads",
        &[("depth_complexity", Int(5)), ("alpha", Float(0.4))],
    );
    let n = 32;
    let mut per_seed = Vec::new();
    for seed in 0..n {
        let (img, truth) = run(&s, 4, 1, false, seed);
        let mut e = [0.0f64; 4];
        for (a, b) in img.iter().zip(&truth) {
            for c in 0..4 {
                e[c] += (a[c] as f64 - b[c]) / img.len() as f64;
            }
        }
        per_seed.push(e);
    }
    for c in 0..4 {
        let mean = per_seed.iter().map(|e| e[c]).sum::<f64>() / n as f64;
        let var = per_seed.iter().map(|e| (e[c] - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let se = (var / n as f64).sqrt();
        assert!(
            se > 1e-4,
            "channel {c}: the estimate varies between seeds (se {se})"
        );
        assert!(
            mean.abs() <= 4.0 * se + 1e-6,
            "channel {c}: mean error {mean:.2e} vs standard error {se:.2e}: biased"
        );
    }
}

#[test]
fn the_correction_makes_alpha_exact_and_lowers_the_error() {
    let s = scene(
        "quads",
        &[("depth_complexity", Int(5)), ("alpha", Float(0.4))],
    );
    let (mut plain, mut corrected) = (0.0, 0.0);
    for seed in 0..6 {
        let (img, truth) = run(&s, 4, 1, true, seed);
        for (a, b) in img.iter().zip(&truth) {
            // Where any sample saw a fragment, alpha is the exact total (f32 products, ≤ 5 layers).
            if a[3] > 0.0 {
                assert!(
                    (a[3] as f64 - b[3]).abs() < 1e-5,
                    "alpha {} vs {}",
                    a[3],
                    b[3]
                );
            }
        }
        corrected += rmse(&img, &truth);
        let (img, truth) = run(&s, 4, 1, false, seed);
        plain += rmse(&img, &truth);
    }
    assert!(
        corrected < plain,
        "corrected {corrected} vs uncorrected {plain} (summed over 6 seeds)"
    );
}

#[test]
fn a_seed_gives_the_same_frame_and_another_seed_another() {
    let s = scene("shells", &[("count", Int(2)), ("segments", Int(12))]);
    let (a, _) = run(&s, 4, 2, true, 3);
    let (b, _) = run(&s, 4, 2, true, 3);
    let (c, _) = run(&s, 4, 2, true, 4);
    assert_eq!(a, b);
    assert_ne!(a, c);
    // Opaque layers are exact at any seed: α = 1 keeps every sample (⌊S + ξ⌋ = S).
    let o = scene(
        "quads",
        &[("depth_complexity", Int(3)), ("alpha", Float(1.0))],
    );
    let (img, truth) = run(&o, 4, 1, false, 9);
    let worst = img
        .iter()
        .zip(&truth)
        .flat_map(|(a, b)| (0..4).map(move |k| (a[k] as f64 - b[k]).abs()))
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "opaque: {worst}");
}
