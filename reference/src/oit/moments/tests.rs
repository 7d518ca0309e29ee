use super::super::testing::*;
use super::*;
use rand::Rng;

const STORAGES: [MomentStorage; 3] = [
    MomentStorage::F64,
    MomentStorage::F32,
    MomentStorage::Unorm16,
];

/// Every moment set of the paper.
fn sets() -> Vec<(MomentKind, u32)> {
    let mut v: Vec<_> = [4, 6, 8].map(|c| (MomentKind::Power, c)).to_vec();
    v.extend([2, 3, 4].map(|c| (MomentKind::Trigonometric, c)));
    v
}

fn cfg(kind: MomentKind, count: u32, storage: MomentStorage) -> MomentConfig {
    MomentConfig::new(kind, count, storage, 1.0, 10.0).unwrap()
}

fn state(frags: &[RefFragment], cfg: &MomentConfig) -> MomentState<f64> {
    let f: Vec<Frag<f64>> = frags.iter().map(Frag::of).collect();
    accumulate(&f, cfg)
}

/// Exact transmittance in front of view distance z.
fn exact_t(frags: &[RefFragment], z: f64) -> f64 {
    frags
        .iter()
        .filter(|f| f.view_z < z)
        .map(|f| 1.0 - f.color[3])
        .product()
}

/// The tolerance of a reconstruction near isolated layers: the bias mixes β of a spread-out
/// moment vector into a point mass, which spreads the reconstructed support by O(√β) in
/// warped depth (variance ~β); measured ≤ 0.1·√β in 32 bits. 16-bit storage uses a larger
/// bias vector and adds 2⁻¹⁷ of quantisation per moment: measured ≤ 2·√β.
fn layer_tol(c: &MomentConfig) -> f64 {
    let k = if c.storage == MomentStorage::Unorm16 {
        4.0
    } else {
        1.0
    };
    k * c.bias.sqrt()
}

#[test]
fn quantisation_maps_single_depths_into_the_unit_cube_and_inverts() {
    for count in [4u32, 6, 8] {
        let off = quant::offset(count);
        for i in 0..=200 {
            let z = -1.0 + i as f64 / 100.0;
            let b: Vec<f64> = (1..=count as i32).map(|j| z.powi(j)).collect();
            let q = quant::quantize(&b);
            // The point of the paper's matrices: every depth's moments land in [0, 1] (so
            // every mixture does, being a convex combination), fit for unorm16.
            for (qi, oi) in q.iter().zip(&off) {
                assert!(
                    (-1e-9..=1.0 + 1e-9).contains(&(qi + oi)),
                    "{count} moments, z {z}: {q:?}"
                );
            }
            let back = quant::dequantize(&q);
            for (x, y) in back.iter().zip(&b) {
                // The published constants carry 11–15 digits.
                assert!(
                    (x - y).abs() < 1e-8,
                    "{count} moments, z {z}: {back:?} vs {b:?}"
                );
            }
        }
    }
}

#[test]
fn one_layer_resolves_exactly_with_normalisation() {
    for (kind, count) in sets() {
        for storage in STORAGES {
            let c = cfg(kind, count, storage);
            for z in [1.2, 3.0, 5.0, 9.5] {
                for a in [0.01, 0.05, 0.5, 0.95] {
                    let px = [frag(z, [0.3, 0.6, 0.9, a], 0)];
                    // A = 1 − exp(−b₀) = α, C = A·(Tαc)/(Tα) = α·c whatever T is; b₀ is stored
                    // in f32 except for F64, a relative 6e-8.
                    let tol = if storage == MomentStorage::F64 {
                        1e-12
                    } else {
                        1e-7
                    };
                    let got = moments(&px, &c);
                    assert!(
                        max_abs(got, exact(&px)) < tol,
                        "{kind:?} {count} {storage:?}: {got:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn one_layer_transmittance_is_a_step_within_the_bias_bound() {
    for (kind, count) in sets() {
        for storage in STORAGES {
            let c = cfg(kind, count, storage);
            let tol = layer_tol(&c);
            for zf in [1.5, 3.0, 5.0, 8.0] {
                for a in [0.05, 0.5, 0.95] {
                    let px = [frag(
                        zf,
                        [0.5; 3]
                            .into_iter()
                            .chain([a])
                            .collect::<Vec<_>>()
                            .try_into()
                            .unwrap(),
                        0,
                    )];
                    let st = state(&px, &c);
                    for dz in [0.05, 0.1, 0.3] {
                        let before = transmittance_at(&st, zf * (1.0 - dz), &c);
                        let after = transmittance_at(&st, zf * (1.0 + dz), &c);
                        let what = format!("{kind:?} {count} {storage:?} z {zf} α {a} ±{dz}");
                        assert!((before - 1.0).abs() <= tol, "{what}: before {before}");
                        assert!((after - (1.0 - a)).abs() <= tol, "{what}: after {after}");
                    }
                    // At the layer itself the reconstruction weights its own mass by
                    // `overestimation`: T = (1 − α)^0.25.
                    let at = transmittance_at(&st, zf, &c);
                    assert!(
                        (at - (1.0 - a).powf(0.25)).abs() <= tol,
                        "{kind:?} {count}: at {at}"
                    );
                }
            }
        }
    }
}

#[test]
fn up_to_m_layers_are_reconstructed_between_them() {
    // m + 1 support points represent any m layers (m = count/2 power, count trig): between
    // well-separated layers T is exact up to the bias's spreading. Two checks: the mathematics
    // with a tiny bias in f64, and the paper's bias in f32 storage.
    let mut rng = rng(82);
    for (kind, count) in sets() {
        let m = if kind == MomentKind::Power {
            count / 2
        } else {
            count
        } as usize;
        let paper = cfg(kind, count, MomentStorage::F32);
        let mut tiny = cfg(kind, count, MomentStorage::F64);
        tiny.bias = 1e-10;
        let mut worst = [0.0f64; 2];
        for _ in 0..50 {
            // Layers spaced evenly in log depth (the warp's metric) over 1.5–8, jittered ±10 %
            // of the spacing (staying inside the warp's 1–10), neighbours ≥ 0.8 spacings apart.
            let step = (8.0f64 / 1.5).ln() / (m - 1).max(1) as f64;
            let px: Vec<RefFragment> = (0..m)
                .map(|i| {
                    let z = 1.5 * (step * (i as f64 + rng.random_range(-0.1..0.1))).exp();
                    frag(z, [0.5, 0.5, 0.5, rng.random_range(0.05..0.9)], i as u32)
                })
                .collect();
            let mut zs: Vec<f64> = px
                .windows(2)
                .map(|w| (w[0].view_z * w[1].view_z).sqrt())
                .collect();
            zs.push(1.0);
            zs.push(10.0);
            for (w, c) in worst.iter_mut().zip([&tiny, &paper]) {
                let st = state(&px, c);
                for &z in &zs {
                    *w = w.max((transmittance_at(&st, z, c) - exact_t(&px, z)).abs());
                }
            }
        }
        eprintln!("{kind:?} {count}: {m} layers, worst {:.2e} (β 1e-10, f64) {:.2e} (paper's β, f32), √β {:.2e}", worst[0], worst[1], paper.bias.sqrt());
        // β = 1e-10 spreads the support by ~1e-5: the closed-form roots and the LDLᵀ stay well
        // inside 1e-4 in f64.
        assert!(worst[0] <= 1e-4, "{kind:?} {count}: {worst:?}");
        // With the paper's β the m layers leave one support point for the bias's spread-out
        // mass, so the O(√β) spreading of one layer applies to all: measured ≤ 2.2·√β for 8
        // power moments, ≤ 0.02·√β for the others.
        assert!(
            worst[1] <= 4.0 * paper.bias.sqrt(),
            "{kind:?} {count}: {worst:?}"
        );
    }
}

#[test]
fn transmittance_stays_in_the_unit_interval_and_power_moments_are_monotone() {
    let mut rng = rng(83);
    let pixels: Vec<_> = (0..100)
        .map(|_| {
            let n = rng.random_range(1..80);
            pixel(&mut rng, n, 0.02, 0.95, 1.0, 10.0)
        })
        .collect();
    for (kind, count) in sets() {
        for storage in STORAGES {
            let c = cfg(kind, count, storage);
            let mut max_rise: f64 = 0.0;
            for px in &pixels {
                let st = state(px, &c);
                let mut prev = 1.0;
                for i in 0..200 {
                    let t = transmittance_at(&st, 1.0 + 9.0 * i as f64 / 199.0, &c);
                    assert!(
                        (0.0..=1.0).contains(&t),
                        "{kind:?} {count} {storage:?}: T {t}"
                    );
                    max_rise = max_rise.max(t - prev);
                    prev = t;
                }
                assert_valid(moments(px, &c), "moments");
            }
            // Power moments interpolate between a lower and an upper bound of the absorbance in
            // front, both monotone in depth. Trigonometric ones are not bounds (the wrapping
            // zone counts roots near 2π partly in front): their T can rise, which is reported.
            eprintln!("{kind:?} {count} {storage:?}: largest rise of T with depth {max_rise:.2e}");
            if kind == MomentKind::Power {
                assert!(
                    max_rise <= 1e-9,
                    "{kind:?} {count} {storage:?}: T rises by {max_rise}"
                );
            }
        }
    }
}

/// Mean over seeded smoke-like pixels (40 layers, α 0.02–0.3) of the max channel error vs exact.
fn mean_error(kind: MomentKind, count: u32, storage: MomentStorage) -> f64 {
    let mut rng = rng(84);
    let c = cfg(kind, count, storage);
    let n = 300;
    (0..n)
        .map(|_| {
            let px = pixel(&mut rng, 40, 0.02, 0.3, 1.0, 10.0);
            max_abs(moments(&px, &c), exact(&px))
        })
        .sum::<f64>()
        / n as f64
}

#[test]
fn error_shrinks_as_moments_increase() {
    for storage in [MomentStorage::F32, MomentStorage::Unorm16] {
        for kind in [MomentKind::Power, MomentKind::Trigonometric] {
            let counts = if kind == MomentKind::Power {
                [4, 6, 8]
            } else {
                [2, 3, 4]
            };
            let e = counts.map(|c| mean_error(kind, c, storage));
            eprintln!("{kind:?} {storage:?} {counts:?}: mean error {e:?}");
            // Each step must gain at least 5 % (measured: 15–30 %); 300 pixels make the mean's
            // sampling noise far smaller than that.
            assert!(
                e[1] < 0.95 * e[0] && e[2] < 0.95 * e[1],
                "{kind:?} {storage:?}: {e:?}"
            );
            assert!(e.iter().all(|x| x.is_finite() && *x < 0.1));
        }
    }
}

#[test]
fn moments_are_order_independent_up_to_rounding() {
    let mut rng = rng(85);
    for (kind, count) in sets() {
        for storage in STORAGES {
            let c = cfg(kind, count, storage);
            let mut worst: f64 = 0.0;
            for _ in 0..50 {
                let px = pixel(&mut rng, 60, 0.02, 0.5, 1.0, 10.0);
                worst = worst.max(max_abs(moments(&px, &c), moments(&arrival(&px), &c)));
            }
            eprintln!("{kind:?} {count} {storage:?}: order changes the image by ≤ {worst:.2e}");
            // F64: sums are exact up to 1e-16 per add. F32: additive blending's summation order
            // (2⁻²⁴ per add) passes through a reconstruction that amplifies it. Unorm16: each
            // fragment re-quantises the normalised moments, so order matters at 2⁻¹⁶.
            let tol = match storage {
                MomentStorage::F64 => 1e-9,
                MomentStorage::F32 => 1e-4,
                MomentStorage::Unorm16 => 2e-2,
            };
            assert!(worst <= tol, "{kind:?} {count} {storage:?}: {worst}");
        }
    }
}

#[test]
fn f32_twin_follows_the_f64_twin() {
    // What a GPU test comparing an f32 implementation with the f32 twin can not expect better
    // than: the f64 twin with the same (f32) storage, over smoke-like pixels.
    let mut rng = rng(86);
    for (kind, count) in sets() {
        for storage in [MomentStorage::F32, MomentStorage::Unorm16] {
            let c = cfg(kind, count, storage);
            let mut worst: f64 = 0.0;
            for _ in 0..100 {
                let px = arrival(&pixel(&mut rng, 60, 0.02, 0.5, 1.0, 10.0));
                let f: Vec<Frag<f32>> = px.iter().map(Frag::of).collect();
                worst = worst.max(max_abs(to_f64(moments_t(&f, &c).rgba), moments(&px, &c)));
            }
            eprintln!("{kind:?} {count} {storage:?}: f32 vs f64 arithmetic ≤ {worst:.2e}");
            assert!(worst <= 1e-3, "{kind:?} {count} {storage:?}: {worst}");
        }
    }
}

#[test]
fn unnormalised_resolve_sees_each_layer_through_the_overestimated_transmittance() {
    for (kind, count) in sets() {
        let mut c = cfg(kind, count, MomentStorage::F32);
        c.normalize = false;
        let a = 0.5;
        let px = [frag(3.0, [0.2, 0.4, 0.8, a], 0)];
        let got = moments(&px, &c);
        // C = T(z)·α·c with T(z) = (1 − α)^overestimation; A stays exact.
        let t = (1.0f64 - a).powf(0.25);
        for ch in 0..3 {
            assert!(
                (got[ch] - t * a * px[0].color[ch]).abs() <= layer_tol(&c),
                "{kind:?} {count}: {got:?}"
            );
        }
        assert!((got[3] - a).abs() < 1e-7);
    }
}

#[test]
fn nearly_transparent_pixels_resolve_to_nothing_and_opaque_ones_stay_finite() {
    let c = cfg(MomentKind::Power, 6, MomentStorage::F32);
    // Total opacity below 0.001: the paper's cut-off drops the pixel.
    let px = [frag(2.0, [1.0, 1.0, 1.0, 0.0009], 0)];
    assert_eq!(moments(&px, &c), [0.0; 4]);
    // α = 1 clamps its absorbance to 10: finite, A = 1 − e⁻¹⁰.
    let px = [
        frag(2.0, [1.0, 0.5, 0.25, 1.0], 0),
        frag(4.0, [0.1, 0.1, 0.1, 1.0], 1),
    ];
    let got = moments(&px, &c);
    assert_valid(got, "opaque");
    assert!((got[3] - (1.0 - (-20.0f64).exp())).abs() < 1e-7, "{got:?}");
}

#[test]
fn bad_moment_counts_and_ranges_are_errors() {
    let e = MomentConfig::new(MomentKind::Power, 5, MomentStorage::F32, 1.0, 10.0).unwrap_err();
    assert!(e.to_string().contains("5"), "{e}");
    assert!(
        MomentConfig::new(MomentKind::Trigonometric, 8, MomentStorage::F32, 1.0, 10.0).is_err()
    );
    assert!(MomentConfig::new(MomentKind::Power, 4, MomentStorage::F32, 0.0, 10.0).is_err());
    let c = cfg(MomentKind::Trigonometric, 3, MomentStorage::Unorm16);
    assert_eq!((c.reals(), c.moment_bytes_per_pixel()), (6, 16));
}
