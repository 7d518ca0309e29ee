//! CPU-twin tests of the packings, the routing and the equalisation (no GPU).

use super::*;

#[test]
fn packings_are_positive_normal_finite_and_nonzero_at_the_extremes() {
    // MAX blending and flush-to-zero must leave every packed value intact and ≠ 0 (empty).
    let extremes = [0.0f32, 1.0, -1.0, 2.0, 0.5];
    for &r in &extremes {
        for &a in &extremes {
            let c = [r, 1.0 - r, r, a];
            for v in [
                pack_color(c),
                pack_keyed(0, c),
                pack_keyed(126, c),
                pack_keyed(500, c),
            ] {
                assert!(
                    v.is_finite() && v.is_normal() && v > 0.0,
                    "{c:?} packs to {v:e}"
                );
            }
        }
    }
}

#[test]
fn pack_color_round_trips_within_half_a_step() {
    for i in 0..=50 {
        let x = i as f32 / 50.0;
        let c = [x, 1.0 - x, (x * 7.0).fract(), (x * 3.0).fract()];
        let u = unpack_color(pack_color(c));
        for k in 0..3 {
            assert!((u[k] - c[k]).abs() <= 0.5 / 127.0 + 1e-6, "{c:?} → {u:?}");
        }
        assert!((u[3] - c[3]).abs() <= 0.5 / 1015.0 + 1e-6, "{c:?} → {u:?}");
    }
}

#[test]
fn pack_keyed_orders_by_key_first_and_keeps_the_colour() {
    let bright = [1.0, 1.0, 1.0, 1.0];
    let dark = [0.0, 0.0, 0.0, 0.0];
    for key in 0..126 {
        assert!(
            pack_keyed(key + 1, dark) > pack_keyed(key, bright),
            "key {key}"
        );
        assert_eq!(keyed_key(pack_keyed(key, bright)), key);
        assert_eq!(keyed_color(pack_keyed(key, bright)), bright);
    }
}

#[test]
fn uniform_routing_puts_the_extremes_in_the_first_and_last_bucket() {
    for &reversed in &[false, true] {
        let (near, far) = if reversed {
            (0.9f32, 0.2f32)
        } else {
            (0.2, 0.9)
        };
        let (zmin, zmax) = (0.2, 0.9);
        assert_eq!(
            uniform_bucket(rel_position(near, zmin, zmax, reversed), 8),
            0
        );
        assert_eq!(
            uniform_bucket(rel_position(far, zmin, zmax, reversed), 8),
            7
        );
        // A pixel with one fragment (zero span) routes it to bucket 0.
        assert_eq!(rel_position(0.5, 0.5, 0.5, reversed), 0.0);
    }
}

#[test]
fn adp_equalise_lists_occupied_bins_nearest_first_in_passes_of_k() {
    // Bins 3, 40, 41 and 70 of 96.
    let hist = [1u32 << 3, (1 << 8) | (1 << 9), 1 << 6];
    assert_eq!(adp_equalise(&hist, 2, 0), vec![3, 40]);
    assert_eq!(adp_equalise(&hist, 2, 1), vec![41, 70]);
    assert_eq!(adp_equalise(&hist, 2, 2), vec![u32::MAX, u32::MAX]);
    assert_eq!(
        adp_equalise(&hist, 8, 0),
        vec![3, 40, 41, 70, u32::MAX, u32::MAX, u32::MAX, u32::MAX]
    );
}

#[test]
fn twin_capacity_per_bucket_single_paired_two_pass() {
    let r = |bucket, key| Routed {
        index: 0,
        t: 0.0,
        bucket,
        key,
        margin: 1.0,
    };
    // Three fragments in bucket 0 (keys 5, 5, 9), one in bucket 3.
    let routed = [r(0, 5), r(0, 5), r(0, 9), r(3, 1)];
    let cfg = |kind| Config { kind, buckets: 8 };
    assert_eq!(
        captured_in_pixel(&cfg(Kind::Uniform { paired: false }), &routed),
        2
    );
    assert_eq!(
        captured_in_pixel(&cfg(Kind::Uniform { paired: true }), &routed),
        3
    );
    assert_eq!(
        captured_in_pixel(&cfg(Kind::TwoPass { paired: false }), &routed),
        3
    );
    // Same key only: paired and two-pass cannot tell them apart.
    let tied = [r(1, 7), r(1, 7)];
    assert_eq!(
        captured_in_pixel(&cfg(Kind::Uniform { paired: true }), &tied),
        1
    );
    assert_eq!(
        captured_in_pixel(&cfg(Kind::TwoPass { paired: false }), &tied),
        1
    );
}

#[test]
fn box_clipped_is_true_only_when_a_corner_leaves_the_near_or_far_plane() {
    // The quads' camera sits at z = 10 (near 1, far 100), looking at the origin.
    let scene = testing::quads_at(&[0.0, 1.0], 0.5);
    let cam = bench_core::gpu_scene::camera_uniform(&scene, 32, 32).clip_from_world;
    assert!(!box_clipped(&cam, [-1.0; 3], [1.0; 3]));
    // Around the eye, and beyond the far plane.
    assert!(box_clipped(&cam, [-1.0, -1.0, 0.0], [1.0, 1.0, 11.0]));
    assert!(box_clipped(&cam, [-1.0, -1.0, -200.0], [1.0, 1.0, 0.0]));
}

#[test]
fn padded_box_contains_every_position_with_room() {
    let ps = [[0.0, 0.0, 0.0], [2.0, -1.0, 0.5], [1.0, 1.0, 0.0]];
    let (lo, hi) = padded_box(&ps);
    for p in ps {
        for a in 0..3 {
            assert!(
                lo[a] < p[a] && p[a] < hi[a],
                "{p:?} not strictly inside {lo:?}..{hi:?}"
            );
        }
    }
    assert_eq!(box_triangles(lo, hi).len(), 36);
}

/// §1.3's premise, on the f64 reference: every fragment of the scene lies in its pixel's box
/// range, and every pixel with a fragment is covered by the box. Tilted shells (many depths per
/// pixel, silhouettes everywhere) and quads under both depth conventions.
#[test]
fn bounding_box_range_contains_every_reference_fragment_depth() {
    let shells = {
        let p = scenarios::Params::new()
            .with("count", scenarios::ParamValue::Int(3))
            .with("segments", scenarios::ParamValue::Int(12));
        scenarios::SceneSpec::new("shells", p)
            .build()
            .expect("shells")
    };
    for (name, scene) in [
        ("shells", shells),
        ("quads", testing::quads(6, 4)),
        ("quads reversed", testing::quads_z(6, 4, true)),
    ] {
        let size = 48;
        let lists = mfx_reference::rasterize(&scene, size, size);
        let ranges = testing::box_ranges(&scene, size);
        let mut covered = 0;
        for (p, range) in ranges.iter().enumerate().take(lists.pixels()) {
            let frags = lists.pixel(p);
            if frags.is_empty() {
                continue;
            }
            let (lo, hi) = range.unwrap_or_else(|| {
                panic!("{name}: pixel {p} has {} fragments, no box", frags.len())
            });
            for f in frags {
                assert!(
                    lo as f64 <= f.depth + 1e-7 && f.depth <= hi as f64 + 1e-7,
                    "{name}: pixel {p}: depth {} outside the box range [{lo}, {hi}]",
                    f.depth
                );
            }
            covered += 1;
        }
        assert!(
            covered > 100,
            "{name}: only {covered} pixels hold fragments"
        );
    }
}
