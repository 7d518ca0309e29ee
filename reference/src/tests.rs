//! Hand-made cases with known answers.

use glam::{DVec3, Vec3};
use scenarios::{Camera, Mesh, Params, Scene, SceneSpec};

use super::*;

/// An orthographic-like setup: camera at z = 10 looking at the origin.
fn scene_with(mesh: Mesh) -> Scene {
    let cam = Camera::look_at(DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO, 30.0, 1.0, 100.0);
    Scene::new(SceneSpec::new("test", Params::new()), mesh, cam)
}

fn quad(mesh: &mut Mesh, half: f32, z: f32, color: [f32; 4], id: u32) {
    let c = [
        Vec3::new(-half, -half, z),
        Vec3::new(half, -half, z),
        Vec3::new(half, half, z),
        Vec3::new(-half, half, z),
    ];
    mesh.push_quad(c, color, id);
}

#[test]
fn two_overlapping_quads_composite_under_in_depth_order() {
    // 32×32 px; the near quad is red α=0.5, the far one blue α=0.5, drawn far first.
    let mut m = Mesh::default();
    quad(&mut m, 1.0, -1.0, [0.0, 0.0, 1.0, 0.5], 1);
    quad(&mut m, 0.5, 1.0, [1.0, 0.0, 0.0, 0.5], 0);
    let s = scene_with(m);
    let fl = rasterize(&s, 32, 32);
    let centre = fl.at(16, 16);
    assert_eq!(centre.len(), 2, "centre pixel sees both quads");
    assert!(centre[0].depth < centre[1].depth);
    assert_eq!(
        centre[0].object_id, 0,
        "near (red) quad first although drawn second"
    );
    let img = fl.composite();
    let p = img[16 * 32 + 16];
    // red: 0.5·1 = 0.5; blue: (1 − 0.5)·0.5·1 = 0.25; alpha: 0.5 + 0.5·0.5 = 0.75.
    let want = [0.5, 0.0, 0.25, 0.75];
    for c in 0..4 {
        assert!(
            (p[c] - want[c]).abs() < 1e-12,
            "channel {c}: {} vs {}",
            p[c],
            want[c]
        );
    }
    // Far quad: ±1 at distance 11 with a 30° fov spans ±5.4 px around the centre; the near one
    // ±3.3 px: pixel (12,12) sees the far quad only.
    assert_eq!(fl.at(12, 12).len(), 1);
    assert_eq!(fl.at(12, 12)[0].object_id, 1);
    assert_eq!(fl.at(0, 0).len(), 0);
}

#[test]
fn shared_edges_cover_every_pixel_exactly_once() {
    // A fan of triangles through the image centre; pixel centres lie exactly on shared edges.
    let mut m = Mesh::default();
    let n = 16;
    let r = 3.0f32;
    let base = 0u32;
    m.positions.push([0.0, 0.0, 0.0]);
    for i in 0..n {
        let a = std::f32::consts::TAU * i as f32 / n as f32;
        m.positions.push([r * a.cos(), r * a.sin(), 0.0]);
    }
    for _ in 0..=n {
        m.normals.push([0.0, 0.0, 1.0]);
        m.colors.push([1.0, 1.0, 1.0, 1.0]);
        m.object_ids.push(0);
    }
    for i in 0..n {
        m.indices.extend_from_slice(&[base, 1 + i, 1 + (i + 1) % n]);
    }
    let s = scene_with(m);
    let fl = rasterize(&s, 64, 64);
    // Inside the inscribed circle every pixel is covered exactly once.
    let dc = fl.depth_complexity();
    for y in 0..64u32 {
        for x in 0..64u32 {
            let (dx, dy) = (x as f64 + 0.5 - 32.0, y as f64 + 0.5 - 32.0);
            let d = dc[(y * 64 + x) as usize];
            assert!(d <= 1, "pixel ({x},{y}) covered {d} times");
            if (dx * dx + dy * dy).sqrt() < 20.0 {
                assert_eq!(d, 1, "pixel ({x},{y}) inside the fan not covered");
            }
        }
    }
}

#[test]
fn sphere_centre_has_front_and_back_at_known_depths() {
    let sphere = scenarios::scenes::shells::sphere(1.0, 64, [1.0, 1.0, 1.0, 0.5], 0);
    let s = scene_with(sphere);
    let fl = rasterize(&s, 65, 65);
    let c = fl.at(32, 32);
    assert_eq!(
        c.len(),
        2,
        "a ray through a closed sphere enters and leaves once"
    );
    // Eye at z = 10: the front is ~9 away, the back ~11 (tessellation shortens both by < 0.2%).
    assert!(
        (c[0].view_z - 9.0).abs() < 0.01,
        "front view_z {}",
        c[0].view_z
    );
    assert!(
        (c[1].view_z - 11.0).abs() < 0.01,
        "back view_z {}",
        c[1].view_z
    );
    assert!(
        c[0].front_facing && !c[1].front_facing,
        "outward winding: front faces first"
    );
}

#[test]
fn coplanar_triangles_both_kept_in_submission_order() {
    let mut m = Mesh::default();
    quad(&mut m, 1.0, 0.0, [1.0, 0.0, 0.0, 0.5], 0);
    quad(&mut m, 1.0, 0.0, [0.0, 1.0, 0.0, 0.5], 1);
    let s = scene_with(m);
    let fl = rasterize(&s, 32, 32);
    let c = fl.at(16, 16);
    assert_eq!(c.len(), 2);
    assert_eq!(c[0].depth, c[1].depth, "same plane, same depth");
    assert!(c[0].prim < c[1].prim, "ties keep submission order");
}

#[test]
fn reversed_z_sorts_by_larger_depth_first() {
    let mut m = Mesh::default();
    quad(&mut m, 1.0, -1.0, [0.0, 0.0, 1.0, 0.5], 1);
    quad(&mut m, 1.0, 1.0, [1.0, 0.0, 0.0, 0.5], 0);
    let mut s = scene_with(m);
    s.camera.reversed_z = true;
    let fl = rasterize(&s, 16, 16);
    let c = fl.at(8, 8);
    assert_eq!(c.len(), 2);
    assert!(
        c[0].depth > c[1].depth,
        "reversed-Z: nearer has the larger depth"
    );
    assert_eq!(c[0].object_id, 0);
}

#[test]
fn quads_scene_reaches_its_analytic_depth_complexity() {
    for d in [1u32, 5, 12] {
        let spec = SceneSpec::new(
            "quads",
            Params::new().with("depth_complexity", scenarios::ParamValue::Int(d as i64)),
        );
        let s = spec.build().unwrap();
        let fl = rasterize(&s, 64, 64);
        assert_eq!(fl.max_depth_complexity(), d, "quads d={d}");
    }
}

#[test]
fn geometry_behind_the_eye_and_beyond_far_is_clipped() {
    let mut m = Mesh::default();
    quad(&mut m, 1.0, 20.0, [1.0, 0.0, 0.0, 1.0], 0); // behind the eye (eye at z = 10)
    quad(&mut m, 1.0, -200.0, [1.0, 0.0, 0.0, 1.0], 1); // beyond far = 100
    let s = scene_with(m);
    let fl = rasterize(&s, 16, 16);
    assert_eq!(fl.total_fragments(), 0);
}

#[test]
fn depth_ties_are_detected_only_where_fragments_are_within_f32_ulps() {
    let mut m = Mesh::default();
    quad(&mut m, 1.0, 0.0, [1.0, 0.0, 0.0, 0.5], 0);
    quad(&mut m, 1.0, 0.0, [0.0, 1.0, 0.0, 0.5], 1); // coplanar: a tie everywhere it covers
    quad(&mut m, 0.3, 2.0, [0.0, 0.0, 1.0, 0.5], 2); // well separated
    let s = scene_with(m);
    let fl = rasterize(&s, 32, 32);
    let ties = fl.depth_tie_pixels(2);
    let p = 16 * 32 + 16;
    assert!(ties[p], "coplanar pair at the centre is a tie");
    assert!(!ties[0], "empty pixel has no tie");
    let mut m2 = Mesh::default();
    quad(&mut m2, 1.0, 0.0, [1.0, 0.0, 0.0, 0.5], 0);
    quad(&mut m2, 1.0, 1.0, [0.0, 1.0, 0.0, 0.5], 1);
    let fl2 = rasterize(&scene_with(m2), 32, 32);
    assert!(
        !fl2.depth_tie_pixels(2)[p],
        "layers 1 unit apart are no tie"
    );
}

#[test]
fn vertices_far_outside_the_view_give_exact_finite_fragments() {
    // One triangle in the plane z = 0 whose vertices lie at ±1e20 (and one at ±1e3 for
    // comparison): both cover every pixel, at the same depth, with finite attributes. Without
    // the guard-band clip the 1e20 triangle's barycentrics cancel to NaN.
    for far in [1e3f32, 1e20] {
        let mut m = Mesh::default();
        for p in [[-far, -far, 0.0], [far, -far, 0.0], [0.0, far, 0.0]] {
            m.positions.push(p);
            m.normals.push([0.0, 0.0, 1.0]);
            m.colors.push([0.2, 0.4, 0.6, 0.5]);
            m.object_ids.push(0);
        }
        m.indices.extend_from_slice(&[0, 1, 2]);
        let fl = rasterize(&scene_with(m), 16, 16);
        for y in 0..16 {
            for x in 0..16 {
                let f = fl.at(x, y);
                assert_eq!(f.len(), 1, "far {far}: pixel ({x},{y})");
                assert!(f[0].depth.is_finite() && f[0].depth > 0.0 && f[0].depth < 1.0);
                assert!(
                    (f[0].color[1] - 0.4).abs() < 1e-6,
                    "far {far}: {:?}",
                    f[0].color
                );
                assert!(
                    (f[0].view_z - 10.0).abs() < 1e-6,
                    "far {far}: {}",
                    f[0].view_z
                );
            }
        }
    }
}

// ---- the multisampled reference ----

use super::multisample::{
    box_filter_2x2, coverage_lists, resolve, sample_list, sample_list_centre_attributes,
    sample_lists, sample_lists_at, sample_lists_centre_attributes, standard_positions,
};

/// World point on the plane `z` that projects to screen position (sx, sy) of a w×h image
/// (inverting the GPU's f32 matrix in f64; the f32 vertex is then within ~1e-5 px, which the
/// 1/256 snap removes).
fn screen_point(s: &Scene, w: u32, h: u32, sx: f64, sy: f64, z: f64) -> Vec3 {
    let m = s.camera.clip_from_world_gpu(w as f64 / h as f64).as_dmat4();
    let (nx, ny) = (sx / w as f64 * 2.0 - 1.0, 1.0 - sy / h as f64 * 2.0);
    // clip = m·(x, y, z, 1); solve cx − nx·cw = 0, cy − ny·cw = 0 for x, y.
    let row = |r: usize| glam::DVec4::new(m.x_axis[r], m.y_axis[r], m.z_axis[r], m.w_axis[r]);
    let (rx, ry, rw) = (row(0), row(1), row(3));
    let a = rx - rw * nx;
    let b = ry - rw * ny;
    let (c1, c2) = (-(a.z * z + a.w), -(b.z * z + b.w));
    let det = a.x * b.y - a.y * b.x;
    Vec3::new(
        ((c1 * b.y - a.y * c2) / det) as f32,
        ((a.x * c2 - c1 * b.x) / det) as f32,
        z as f32,
    )
}

/// A quad given by its screen rectangle [x0, x1] × [y0, y1] on the plane `z`.
fn screen_quad(s: &mut Scene, w: u32, h: u32, r: [f64; 4], z: f64, color: [f32; 4], id: u32) {
    let [x0, y0, x1, y1] = r;
    let p = |x, y| screen_point(s, w, h, x, y, z);
    let c = [p(x0, y1), p(x1, y1), p(x1, y0), p(x0, y0)];
    s.mesh.push_quad(c, color, id);
}

fn empty_scene() -> Scene {
    scene_with(Mesh::default())
}

/// The mean over sample positions of each sample's composite: the multisampled truth of
/// transparency (what `aa::truth` computes for it).
fn msaa_composite(s: &Scene, w: u32, h: u32, samples: u32) -> Vec<[f64; 4]> {
    let per: Vec<Vec<[f64; 4]>> = sample_lists(s, w, h, samples)
        .iter()
        .map(|l| l.composite())
        .collect();
    resolve(&per)
}

#[test]
fn standard_positions_are_vulkans_table_on_the_sixteenth_grid() {
    for n in [1, 2, 4, 8] {
        let p = standard_positions(n);
        assert_eq!(p.len(), n as usize);
        // On the 1/16 grid, inside the pixel, distinct, and centred on average (the table is
        // symmetric about the centre).
        for &(x, y) in p {
            assert!((x * 16.0).fract() == 0.0 && (y * 16.0).fract() == 0.0);
            assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
        }
        let mean = p.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        assert_eq!((mean.0 / n as f64, mean.1 / n as f64), (0.5, 0.5));
    }
    assert_eq!(standard_positions(4)[0], (0.375, 0.125));
    assert_eq!(standard_positions(8)[7], (0.9375, 0.0625));
}

#[test]
fn a_half_covered_pixel_resolves_to_half_in_every_mode() {
    // An opaque white quad whose left edge runs down the middle of pixel column 8 (x = 8.5) at
    // 32×32: half the samples of 2×, 4×, 8× and of the 2×2 supersamples lie right of it.
    let (w, h) = (32, 32);
    let mut s = empty_scene();
    screen_quad(&mut s, w, h, [8.5, 8.0, 24.0, 24.0], 0.0, [1.0; 4], 0);
    let at = |img: &[[f64; 4]], x: u32, y: u32| img[(y * w + x) as usize];
    for samples in [2, 4, 8] {
        let img = msaa_composite(&s, w, h, samples);
        assert_eq!(at(&img, 8, 16), [0.5; 4], "{samples}×: the cut pixel");
        assert_eq!(at(&img, 9, 16), [1.0; 4], "{samples}×: inside");
        assert_eq!(at(&img, 7, 16), [0.0; 4], "{samples}×: outside");
        // The coverage masks say the same: exactly half the bits at the cut pixel.
        let cl = coverage_lists(&s, w, h, samples);
        let p = (16 * w + 8) as usize;
        let m = cl.masks[cl.lists.offsets[p] as usize];
        assert_eq!(cl.lists.pixel(p).len(), 1);
        assert_eq!(m.count_ones(), samples / 2, "{samples}×: mask {m:#b}");
        assert_eq!(cl.composite_first(usize::MAX)[p], [0.5; 4]);
    }
    let big = rasterize(&s, 2 * w, 2 * h).composite();
    let ssaa = box_filter_2x2(&big, w, h);
    assert_eq!(at(&ssaa, 8, 16), [0.5; 4], "ssaa2x2: the cut pixel");
    assert_eq!(at(&ssaa, 9, 16), [1.0; 4]);
    // One sample at the centre: the centre lies on the (left, so owned) edge.
    assert_eq!(at(&rasterize(&s, w, h).composite(), 8, 16), [1.0; 4]);
}

#[test]
fn shared_edges_through_sample_positions_cover_every_sample_exactly_once() {
    // A grid of quads (each two triangles sharing a diagonal) whose vertical and horizontal
    // edges pass exactly through 2×, 4× and 8× sample positions (x = k + 0.375, y = k + 0.125,
    // …), and a fan of 16 triangles with slanted shared edges: every sample inside is covered
    // by exactly one triangle, in the per-sample lists and in the coverage masks alike.
    let (w, h) = (32, 32);
    let mut s = empty_scene();
    let xs = [3.375, 7.5625, 11.25, 15.9375, 19.75, 23.4375, 28.0625];
    let ys = [3.125, 6.3125, 10.75, 14.8125, 18.25, 22.0625, 27.9375];
    for i in 0..xs.len() - 1 {
        for j in 0..ys.len() - 1 {
            let r = [xs[i], ys[j], xs[i + 1], ys[j + 1]];
            screen_quad(&mut s, w, h, r, 0.0, [1.0; 4], 0);
        }
    }
    let inside = |x: f64, y: f64| x > xs[0] && x < xs[6] && y > ys[0] && y < ys[6];
    let mut on_edge = 0;
    for samples in [1, 2, 4, 8] {
        let pos = standard_positions(samples);
        for (k, lists) in sample_lists(&s, w, h, samples).iter().enumerate() {
            let dc = lists.depth_complexity();
            for y in 0..h {
                for x in 0..w {
                    let (sx, sy) = (x as f64 + pos[k].0, y as f64 + pos[k].1);
                    let d = dc[(y * w + x) as usize];
                    on_edge += (xs.contains(&sx) || ys.contains(&sy)) as u32;
                    if inside(sx, sy) {
                        assert_eq!(
                            d, 1,
                            "{samples}×, sample {k} of ({x},{y}): covered {d} times"
                        );
                    } else {
                        assert!(
                            d <= 1,
                            "{samples}×, sample {k} of ({x},{y}): covered {d} times"
                        );
                    }
                }
            }
        }
        let cl = coverage_lists(&s, w, h, samples);
        for p in 0..cl.lists.pixels() {
            let (a, b) = (
                cl.lists.offsets[p] as usize,
                cl.lists.offsets[p + 1] as usize,
            );
            let mut seen = 0u32;
            for &m in &cl.masks[a..b] {
                assert_eq!(seen & m, 0, "{samples}×: pixel {p} has a sample twice");
                seen |= m;
            }
            let (x, y) = ((p as u32 % w) as f64, (p as u32 / w) as f64);
            let all_inside = pos.iter().all(|&(ox, oy)| inside(x + ox, y + oy));
            if all_inside {
                assert_eq!(
                    seen,
                    (1u32 << samples) - 1,
                    "{samples}×: pixel {p} misses samples"
                );
            }
        }
    }
    assert!(
        on_edge > 100,
        "the grid's edges pass through samples ({on_edge})"
    );

    // The fan of the single-sample test, at 8 samples: no sample twice, none missed inside.
    let mut m = Mesh::default();
    let n = 16;
    m.positions.push([0.0, 0.0, 0.0]);
    for i in 0..n {
        let a = std::f32::consts::TAU * i as f32 / n as f32;
        m.positions.push([3.0 * a.cos(), 3.0 * a.sin(), 0.0]);
    }
    for _ in 0..=n {
        m.normals.push([0.0, 0.0, 1.0]);
        m.colors.push([1.0; 4]);
        m.object_ids.push(0);
    }
    for i in 0..n {
        m.indices.extend_from_slice(&[0, 1 + i, 1 + (i + 1) % n]);
    }
    let fan = scene_with(m);
    for (k, lists) in sample_lists(&fan, 64, 64, 8).iter().enumerate() {
        let (ox, oy) = standard_positions(8)[k];
        for (p, &d) in lists.depth_complexity().iter().enumerate() {
            let (x, y) = ((p % 64) as f64 + ox - 32.0, (p / 64) as f64 + oy - 32.0);
            assert!(d <= 1, "fan: sample {k} of pixel {p} covered {d} times");
            if (x * x + y * y).sqrt() < 20.0 {
                assert_eq!(d, 1, "fan: sample {k} of pixel {p} missed");
            }
        }
    }
}

#[test]
fn one_sample_at_the_centre_is_the_single_sample_reference() {
    for s in [
        SceneSpec::new(
            "grass",
            Params::new().with("blades", scenarios::ParamValue::Int(60)),
        )
        .build()
        .unwrap(),
        SceneSpec::new("shells", Params::new()).build().unwrap(),
    ] {
        let single = rasterize(&s, 48, 40);
        let one = &sample_lists(&s, 48, 40, 1)[0];
        assert_eq!(one.offsets, single.offsets, "{}", s.label());
        assert_eq!(one.frags, single.frags, "{}", s.label());
        let cl = coverage_lists(&s, 48, 40, 1);
        assert_eq!(cl.lists.frags, single.frags);
        assert!(cl.masks.iter().all(|&m| m == 1));
        assert_eq!(cl.composite_first(usize::MAX), single.composite());
        assert_eq!(msaa_composite(&s, 48, 40, 1), single.composite());
    }
}

#[test]
fn coverage_masks_equal_per_sample_lists_where_depth_and_colour_are_constant_in_a_pixel() {
    // Screen-parallel quads of one colour each: a fragment's centre depth and colour are its
    // depth and colour at every sample, so the coverage view composites exactly as the
    // per-sample one (up to the order of f64 additions).
    let s = SceneSpec::new(
        "quads",
        Params::new().with("depth_complexity", scenarios::ParamValue::Int(6)),
    )
    .build()
    .unwrap();
    for samples in [2, 4, 8] {
        let a = msaa_composite(&s, 40, 40, samples);
        let b = coverage_lists(&s, 40, 40, samples).composite_first(usize::MAX);
        let worst = a
            .iter()
            .zip(&b)
            .flat_map(|(x, y)| (0..4).map(move |c| (x[c] - y[c]).abs()))
            .fold(0.0, f64::max);
        assert!(worst < 1e-12, "{samples}×: {worst}");
        // And antialiasing changed something: edge pixels are fractional.
        let single = rasterize(&s, 40, 40).composite();
        assert!(a
            .iter()
            .zip(&single)
            .any(|(x, y)| (x[3] - y[3]).abs() > 0.05));
    }
    // A half-width sample list is what sample_list gives at that position.
    let l = sample_list(&s, 40, 40, (0.25, 0.75));
    assert_eq!(l.pixels(), 1600);
}

/// A random scene over a `w` × `h` image: `n` triangles with corners anywhere over it and beyond
/// its edges, every other one on the 1/16 grid where the sample positions lie (edges through
/// samples, shared corners), at random depths (they intersect), each corner its own colour,
/// alpha and normal (attributes vary across every pixel).
fn random_scene(w: u32, h: u32, n: u32, seed: u64) -> Scene {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut s = empty_scene();
    for t in 0..n {
        let base = s.mesh.positions.len() as u32;
        for _ in 0..3 {
            let mut x = rng.random_range(-4.0..w as f64 + 4.0);
            let mut y = rng.random_range(-4.0..h as f64 + 4.0);
            if t % 2 == 0 {
                (x, y) = ((x * 16.0).round() / 16.0, (y * 16.0).round() / 16.0);
            }
            let z = rng.random_range(-2.0..2.0);
            let p = screen_point(&s, w, h, x, y, z);
            let c: [f32; 4] = std::array::from_fn(|_| rng.random_range(0.05..1.0));
            let nrm = Vec3::new(rng.random(), rng.random(), 1.0).normalize();
            s.mesh.positions.push(p.into());
            s.mesh.colors.push(c);
            s.mesh.normals.push(nrm.into());
            s.mesh.object_ids.push(t % 5);
        }
        s.mesh
            .indices
            .extend_from_slice(&[base, base + 1, base + 2]);
    }
    s
}

#[test]
fn one_traversal_lists_equal_the_lists_of_each_sample_position() {
    // The multisampled truth rasterises every sample position in one traversal
    // (`rasterize_each`); each position's lists must be exactly those of its own pass: the same
    // fragments (coverage, f64 depth and attributes to the bit) in the same order. For 2×, 4×
    // and 8× MSAA, the 2×2 grid of `ssaa2x2` at one resolution, the per-sample capture's
    // centre-attribute rule, and a mix of samplings of several coverage positions.
    let (w, h) = (37, 29);
    let grid = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];
    for seed in 0..3 {
        let s = random_scene(w, h, 90, seed);
        let sets: Vec<&[(f64, f64)]> = vec![
            standard_positions(2),
            standard_positions(4),
            standard_positions(8),
            &grid,
        ];
        let mut fragments = 0;
        for pos in sets {
            let each = sample_lists_at(&s, w, h, pos);
            let centre = sample_lists_centre_attributes(&s, w, h, pos);
            assert_eq!(each.len(), pos.len());
            for (k, &p) in pos.iter().enumerate() {
                let one = sample_list(&s, w, h, p);
                assert_eq!(each[k].offsets, one.offsets, "seed {seed}, {p:?}");
                assert_eq!(each[k].frags, one.frags, "seed {seed}, {p:?}");
                let one = sample_list_centre_attributes(&s, w, h, p);
                assert_eq!(centre[k].offsets, one.offsets, "seed {seed}, {p:?}");
                assert_eq!(centre[k].frags, one.frags, "seed {seed}, {p:?}");
                fragments += one.frags.len();
            }
        }
        // The scene covers enough to mean something: overlapping layers at many samples.
        assert!(fragments > 4 * (w * h) as usize, "seed {seed}: {fragments}");
        // Samplings of several positions (coverage masks) beside single ones, in one traversal.
        let samplings = [
            raster::CENTRE,
            Sampling {
                coverage: standard_positions(4),
                attributes: (0.5, 0.5),
                depth: None,
            },
            Sampling {
                coverage: standard_positions(8),
                attributes: (0.5, 0.5),
                depth: Some((0.0625, 0.4375)),
            },
            Sampling {
                coverage: &grid[1..2],
                attributes: (0.9375, 0.0625),
                depth: None,
            },
        ];
        let all = raster::rasterize_each(&s, w, h, &samplings);
        for (k, sampling) in samplings.iter().enumerate() {
            let (lists, masks) = rasterize_with(&s, w, h, *sampling);
            assert_eq!(all[k].0.offsets, lists.offsets, "seed {seed}, sampling {k}");
            assert_eq!(all[k].0.frags, lists.frags, "seed {seed}, sampling {k}");
            assert_eq!(all[k].1, masks, "seed {seed}, sampling {k}");
        }
    }
}

#[test]
fn depth_slope_is_the_triangle_s_depth_change_a_pixel() {
    // Depth is linear in screen space over a triangle, so where one triangle covers a pixel and
    // its right and lower neighbours, |Δx depth| + |Δy depth| is its depth_slope (the f32 of it).
    let scene = scenarios::SceneSpec::new(
        "tets",
        scenarios::Params::new().with("cells", scenarios::ParamValue::Int(2)),
    )
    .build()
    .unwrap();
    let (w, h) = (48u32, 48u32);
    let l = rasterize(&scene, w, h);
    let of = |x: u32, y: u32, prim: u32| {
        l.pixel((y * w + x) as usize)
            .iter()
            .find(|f| f.prim == prim)
            .copied()
    };
    let (mut checked, mut steep) = (0usize, 0.0f64);
    for y in 0..h - 1 {
        for x in 0..w - 1 {
            for f in l.pixel((y * w + x) as usize) {
                let (Some(r), Some(d)) = (of(x + 1, y, f.prim), of(x, y + 1, f.prim)) else {
                    continue;
                };
                let slope = (r.depth - f.depth).abs() + (d.depth - f.depth).abs();
                let want = f64::from(f.depth_slope);
                assert!(
                    (slope - want).abs() <= 1e-6 * want + 1e-12,
                    "prim {} at ({x},{y}): {slope:e} a pixel, depth_slope {want:e}",
                    f.prim
                );
                checked += 1;
                steep = steep.max(want);
            }
        }
    }
    assert!(checked > 1000, "{checked} fragments checked");
    assert!(steep > 1e-3, "some triangle is steep: {steep:e}");
}
