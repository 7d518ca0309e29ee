use glam::{DVec3, Vec3};
use scenarios::ParamValue::Int;
use scenarios::{Camera, Mesh, Params, Scene, SceneSpec};

use super::*;
use crate::reference::rasterize;
use crate::testing::{count_mismatch, gpu, max_err, params, run, scene};

/// Composite of up to ~16 layers in f32 vs f64, attributes re-derived from the primitive in f32.
const IMAGE_TOL: f64 = 5e-5;

fn check(name: &str, s: &Scene, w: u32, h: u32, p: &Params) {
    let (cap, lists) = run(&ComputeAbuffer, s, w, h, p);
    assert_eq!(cap.overflow_pixels, Some(0), "{name}: {}", cap.notes);
    assert!(cap.flag.is_none(), "{name}: {:?} {}", cap.flag, cap.notes);
    let (bad, first) = count_mismatch(&cap, &lists, u32::MAX);
    assert_eq!(bad, 0, "{name}: counts differ first at {first:?}");
    let (e, at) = max_err(&cap, &lists);
    assert!(e <= IMAGE_TOL, "{name}: error {e} at pixel {at}");
}

#[test]
fn equals_the_reference_with_small_big_and_all_shared_triangles() {
    let shells = scene("shells", &[("count", Int(4)), ("segments", Int(12))]);
    let grass = scene("grass", &[("blades", Int(300))]);
    let quads = scene("quads", &[("depth_complexity", Int(6))]);
    // small_max 1: (almost) every triangle takes the shared path; 1 << 20: every unclipped one
    // is rasterised by a single thread.
    for small in [1, 128, 1 << 20] {
        let p = params(&[("small_max", Int(small))]);
        for (name, s) in [("shells", &shells), ("grass", &grass), ("quads", &quads)] {
            check(&format!("{name} small_max {small}"), s, 48, 40, &p);
        }
    }
}

fn scene_with(mesh: Mesh, eye_z: f64, near: f64) -> Scene {
    let cam = Camera::look_at(DVec3::new(0.0, 0.0, eye_z), DVec3::ZERO, 60.0, near, 100.0);
    Scene::new(SceneSpec::new("test", Params::new()), mesh, cam)
}

fn tri(mesh: &mut Mesh, v: [[f32; 3]; 3], color: [f32; 4], id: u32) {
    let base = mesh.positions.len() as u32;
    for p in v {
        mesh.positions.push(p);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.colors.push(color);
        mesh.object_ids.push(id);
    }
    mesh.indices.extend_from_slice(&[base, base + 1, base + 2]);
}

#[test]
fn clips_at_the_near_plane_and_the_guard_band_like_the_reference() {
    let mut m = Mesh::default();
    // A floor reaching behind the eye (eye at z = 5): clipped by the near plane into a polygon.
    let c = [Vec3::new(-3.0, -1.0, 20.0), Vec3::new(3.0, -1.0, 20.0)];
    let f = [Vec3::new(3.0, -1.0, -30.0), Vec3::new(-3.0, -1.0, -30.0)];
    m.push_quad([c[0], c[1], f[0], f[1]], [0.2, 0.6, 0.3, 0.5], 0);
    // Vertices at ±1e20: guard-band clipped (without it the edge functions overflow f32).
    tri(
        &mut m,
        [[-1e20, -1e20, 0.0], [1e20, -1e20, 0.0], [0.0, 1e20, 0.0]],
        [0.8, 0.2, 0.1, 0.4],
        1,
    );
    // An ordinary triangle in front, partly off screen.
    tri(
        &mut m,
        [[-0.5, -0.5, 1.0], [4.0, 0.0, 1.0], [0.0, 0.7, 1.0]],
        [0.1, 0.3, 0.9, 0.6],
        2,
    );
    let s = scene_with(m, 5.0, 0.5);
    for small in [1, 128] {
        check(
            &format!("clipped small_max {small}"),
            &s,
            40,
            32,
            &params(&[("small_max", Int(small))]),
        );
    }
}

#[test]
fn allocates_exactly_eight_bytes_per_true_fragment() {
    let s = scene("shells", &[("count", Int(3)), ("segments", Int(10))]);
    let (w, h) = (40u32, 36u32);
    let g = gpu();
    let gs = GpuScene::upload(g, &s, w, h);
    let m = crate::measure::measure(
        g,
        &gs,
        &ComputeAbuffer,
        &crate::testing::point(&ComputeAbuffer, &Params::new()),
        0,
        1,
    )
    .unwrap();
    let total = rasterize(&s, w, h).total_fragments();
    assert!(total > 0);
    let px = (w * h) as u64;
    let blocks = px.div_ceil(SCAN_BLOCK);
    let fixed = px * 4 + px * 16;
    // The big-triangle list (2 words) and chunk table (≤ px / CHUNK + 1 words) per triangle.
    let ntri = s.mesh.indices.len() as u64 / 3;
    let work_max = (COUNTERS + blocks + ntri * (3 + px / CHUNK as u64)) * 4;
    let bytes = m.prepared.bytes_allocated();
    assert!(
        bytes >= fixed + total * FRAG_BYTES && bytes <= fixed + total * FRAG_BYTES + work_max,
        "{bytes} B for {total} fragments ({} B of them, {fixed} B per-pixel)",
        total * FRAG_BYTES
    );
}

#[test]
fn a_fragment_beyond_the_allocation_is_counted_not_written() {
    // Prepare on a scene whose 4 far quads lie behind the eye, then (as a dynamic scene would)
    // move them into view with the same buffers: the extra fragments must be reported.
    let quads = |hidden_z: f32| {
        let mut m = Mesh::default();
        for (i, z) in [
            0.0,
            0.5,
            hidden_z,
            hidden_z + 0.1,
            hidden_z + 0.2,
            hidden_z + 0.3,
        ]
        .into_iter()
        .enumerate()
        {
            let h = 0.8;
            let c = [
                Vec3::new(-h, -h, z),
                Vec3::new(h, -h, z),
                Vec3::new(h, h, z),
                Vec3::new(-h, h, z),
            ];
            m.push_quad(c, [0.5, 0.5, 0.5, 0.3], i as u32);
        }
        scene_with(m, 5.0, 0.5)
    };
    let (small, big) = (quads(10.0), quads(1.0));
    let (total_small, total_big) = (
        rasterize(&small, 32, 32).total_fragments(),
        rasterize(&big, 32, 32).total_fragments(),
    );
    assert!(total_big > total_small);
    let g = gpu();
    // small_max 1 << 20: every triangle on the one-thread path, so fragments past the allocation
    // are counted one by one; at the default the moved quads become shared triangles that the
    // list (sized for none) cannot hold, which is flagged too.
    for small_max in [1 << 20, 128] {
        let gs_small = GpuScene::upload(g, &small, 32, 32);
        let gs_big = GpuScene::upload(g, &big, 32, 32);
        let p = params(&[("small_max", Int(small_max))]);
        let mut prepared = ComputeAbuffer
            .prepare(g, &gs_small, &crate::testing::point(&ComputeAbuffer, &p))
            .unwrap();
        // The bind group holds the small scene's buffers: copy the moved positions over them.
        let mut enc = g.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&gs_big.positions, 0, &gs_small.positions, 0, None);
        g.queue.submit([enc.finish()]);
        let mut timer = crate::timing::GpuTimer::new(g);
        prepared.frame(g, &gs_small, &mut timer).unwrap();
        let cap = prepared.readback(g, &gs_small).unwrap();
        assert_eq!(cap.flag.as_deref(), Some("overflow"), "{}", cap.notes);
        if small_max == 128 {
            assert!(cap.notes.contains("0 shared"), "{}", cap.notes);
            assert!(
                !cap.notes.contains(" 0 big triangles unlisted"),
                "{}",
                cap.notes
            );
            continue;
        }
        assert!(cap.overflow_pixels.unwrap() > 0, "{}", cap.notes);
        let kept: u64 = cap.counts.unwrap().iter().map(|&c| c as u64).sum();
        assert_eq!(
            kept, total_small,
            "every allocated slot is used, none twice"
        );
        let beyond = format!(" {} beyond the allocation", total_big - total_small);
        assert!(cap.notes.contains(&beyond), "{}", cap.notes);
    }
}

#[test]
fn slivers_of_snapped_degenerate_triangles_stay_finite() {
    // The extreme scene's "collinear" triangles are not collinear after f32 rounding: snapped,
    // some cover pixels while their clip-space vertices are (nearly) collinear, where the
    // perspective-correct weights are 0/0.
    let s = scene(
        "extreme",
        &[
            ("coord", scenarios::ParamValue::Float(1e3)),
            ("degenerate", Int(3000)),
        ],
    );
    let (cap, _) = run(&ComputeAbuffer, &s, 96, 96, &Params::new());
    let img = cap.image.unwrap();
    let bad = img.iter().flatten().filter(|v| !v.is_finite()).count();
    assert_eq!(bad, 0, "{bad} non-finite channels; {}", cap.notes);
}
