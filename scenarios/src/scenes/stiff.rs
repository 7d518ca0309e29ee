//! Generators for the stiff and extreme cases of the `stability` suite (issue 5):
//!
//! - `slabs`: a grid of stacks of nested thin closed boxes far from the eye (the thickness
//!   cancellation case: the f32 running sum ±z reaches count × distance).
//! - `csg_pair`: two overlapping closed spheres, object ids 0 and 1 (CSG operands A and B).
//! - `coplanar`: layers of exactly duplicated quads (z-fighting), ids growing with submission.
//! - `extreme`: degenerate (zero-area) triangles, triangles far outside the viewport, and
//!   vertices at ±`coord` (1e7 by default), over a few ordinary quads.

use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::{frame_sphere, palette, shells, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Camera, Result};

/// A closed axis-aligned box with outward normals (counter-clockwise seen from outside).
pub fn cuboid(centre: Vec3, half: Vec3, color: [f32; 4], id: u32) -> Mesh {
    let mut m = Mesh::default();
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (-Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (-Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (-Vec3::Z, Vec3::Y, Vec3::X),
    ];
    for (n, a, b) in faces {
        let c = centre + n * half;
        let (a, b) = (a * half, b * half);
        m.push_quad([c - a - b, c + a - b, c + a + b, c - a + b], color, id);
    }
    m
}

pub fn slabs(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let count = r.int("count", 16, 1, 1024)? as u32;
    let tiles = r.int("tiles", 4, 1, 64)? as u32;
    let distance = r.float("distance", 1e4, 1.0, 1e7)?;
    let wall = r.float("wall", 0.05, 1e-6, 1e3)?;
    let alpha = r.float("alpha", 0.3, 0.0, 1.0)? as f32;
    let reversed_z = r.boolean("reversed_z", false)?;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    r.finish()?;

    let mut rng = Pcg32::seed_from_u64(seed);
    let fovy: f64 = 40.0;
    // The grid fills 80% of the view height at the stack's distance.
    let half_view = (fovy.to_radians() * 0.5).tan() * distance * 0.8;
    let cell = (2.0 * half_view / tiles as f64) as f32;
    let mut mesh = Mesh::default();
    let mut objects = Vec::new();
    let mut deepest = 0.0f32;
    for ty in 0..tiles {
        for tx in 0..tiles {
            let cx = -half_view as f32 + cell * (tx as f32 + 0.5);
            let cy = -half_view as f32 + cell * (ty as f32 + 0.5);
            for i in 0..count {
                // Box i of the stack: half depth wall·(count − i + u), u ∈ [0, ½): nested, never
                // touching, and different in every tile so each tile is its own sample.
                let hz = (wall * ((count - i) as f64 + 0.5 * rng.random::<f64>())) as f32;
                deepest = deepest.max(hz);
                let hxy = cell * 0.45 * (1.0 - 0.5 * i as f32 / count as f32);
                let id = (ty * tiles + tx) * count + i;
                mesh.append(&cuboid(
                    Vec3::new(cx, cy, 0.0),
                    Vec3::new(hxy, hxy, hz),
                    palette(i, alpha),
                    id,
                ));
                objects.push(ObjectInfo {
                    name: format!("slab{tx}_{ty}_{i}"),
                    closed: true,
                });
            }
        }
    }
    // Near and far hug the stacks, so window depth resolves the layers even at 1e7.
    let margin = 4.0 * deepest as f64 + 1.0;
    let mut camera = Camera::look_at(
        DVec3::new(0.0, 0.0, distance),
        DVec3::ZERO,
        fovy,
        (distance - margin).max(distance * 0.5),
        distance + margin,
    );
    camera.reversed_z = reversed_z;
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    scene.analytic_max_depth_complexity = Some(2 * count);
    Ok(scene)
}

pub fn csg_pair(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let offset = r.float("offset", 0.5, 0.0, 2.0)? as f32;
    let segments = r.int("segments", 24, 3, 512)? as u32;
    let alpha = r.float("alpha", 1.0, 0.0, 1.0)? as f32;
    let shape = r.string("shape", "sphere", &["sphere", "box"])?;
    r.finish()?;
    let mut mesh = Mesh::default();
    let mut objects = Vec::new();
    for (id, dx, dz) in [(0u32, -offset, 0.1f32), (1, offset, -0.1)] {
        let mut m = if shape == "sphere" {
            shells::sphere(1.0, segments, palette(id, alpha), id)
        } else {
            cuboid(Vec3::ZERO, Vec3::splat(0.8), palette(id, alpha), id)
        };
        for p in &mut m.positions {
            p[0] += dx;
            p[2] += dz;
        }
        mesh.append(&m);
        objects.push(ObjectInfo {
            name: ["A", "B"][id as usize].into(),
            closed: true,
        });
    }
    let mut scene = Scene::new(spec.clone(), mesh, frame_sphere(1.0 + offset as f64, 45.0));
    scene.objects = objects;
    scene.analytic_max_depth_complexity = Some(4);
    Ok(scene)
}

pub fn coplanar(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let layers = r.int("layers", 3, 1, 256)? as u32;
    let copies = r.int("copies", 2, 1, 64)? as u32;
    let alpha = r.float("alpha", 0.35, 0.0, 1.0)? as f32;
    let reversed_z = r.boolean("reversed_z", false)?;
    r.finish()?;
    let mut mesh = Mesh::default();
    let mut objects = Vec::new();
    let fovy: f64 = 50.0;
    let distance = 4.0;
    let half = ((fovy.to_radians() * 0.5).tan() * distance) as f32;
    for l in 0..layers {
        let z = 1.0 - 2.0 * (l as f32 + 0.5) / layers as f32;
        let e = half * (0.9 - 0.5 * l as f32 / layers as f32);
        for c in 0..copies {
            // Identical vertices: the copies rasterize to bit-identical depths.
            let id = l * copies + c;
            let corners = [
                Vec3::new(-e, -e, z),
                Vec3::new(e, -e, z),
                Vec3::new(e, e, z),
                Vec3::new(-e, e, z),
            ];
            mesh.push_quad(corners, palette(id, alpha), id);
            objects.push(ObjectInfo {
                name: format!("layer{l}copy{c}"),
                closed: false,
            });
        }
    }
    let mut camera = Camera::look_at(
        DVec3::new(0.0, 0.0, distance),
        DVec3::ZERO,
        fovy,
        0.1,
        100.0,
    );
    camera.reversed_z = reversed_z;
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    scene.analytic_max_depth_complexity = Some(layers * copies);
    Ok(scene)
}

pub fn extreme(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let coord = r.float("coord", 1e7, 1.0, 1e30)? as f32;
    let degenerate = r.int("degenerate", 64, 0, 1 << 20)? as u32;
    let alpha = r.float("alpha", 0.4, 0.0, 1.0)? as f32;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    r.finish()?;
    let mut rng = Pcg32::seed_from_u64(seed);
    let mut mesh = Mesh::default();
    let mut objects = Vec::new();
    let mut id = 0u32;
    let push_tri = |mesh: &mut Mesh, v: [Vec3; 3], id: u32| {
        let base = mesh.positions.len() as u32;
        for p in v {
            mesh.positions.push(p.into());
            mesh.normals.push([0.0, 0.0, 1.0]);
            mesh.colors.push(palette(id, alpha));
            mesh.object_ids.push(id);
        }
        mesh.indices.extend_from_slice(&[base, base + 1, base + 2]);
    };
    // Two ordinary quads in the middle.
    for (i, z) in [0.5f32, -0.5].into_iter().enumerate() {
        let e = 1.0 - 0.3 * i as f32;
        mesh.push_quad(
            [
                Vec3::new(-e, -e, z),
                Vec3::new(e, -e, z),
                Vec3::new(e, e, z),
                Vec3::new(-e, e, z),
            ],
            palette(id, alpha),
            id,
        );
        id += 1;
    }
    // A huge triangle covering the whole view, every vertex at ±coord in x or y.
    push_tri(
        &mut mesh,
        [
            Vec3::new(-coord, -coord, -1.0),
            Vec3::new(coord, -coord, -1.0),
            Vec3::new(0.0, coord, -1.0),
        ],
        id,
    );
    id += 1;
    // Triangles with one vertex at ±coord in x, y or z (through the near plane, behind the eye).
    for k in 0..6 {
        let axis = k % 3;
        let sign = if k < 3 { 1.0 } else { -1.0 };
        let mut far = Vec3::ZERO;
        far[axis] = sign * coord;
        let a = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            0.2 * k as f32 - 0.6,
        );
        let b = a + Vec3::new(0.3, 0.05, 0.0);
        push_tri(&mut mesh, [a, b, far], id);
        id += 1;
    }
    // Zero-area triangles: a repeated vertex, three collinear vertices, all three equal.
    for k in 0..degenerate {
        let p = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let d = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            0.0,
        );
        let v = match k % 3 {
            0 => [p, p, p + d],
            1 => [p, p + d, p + 2.0 * d],
            _ => [p, p, p],
        };
        push_tri(&mut mesh, v, id);
    }
    objects.push(ObjectInfo {
        name: "extreme".into(),
        closed: false,
    });
    let camera = Camera::look_at(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO, 50.0, 0.1, 100.0);
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    Ok(scene)
}
