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
