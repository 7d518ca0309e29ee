//! `city`: a ground plane with a grid of box buildings (or a closed room, which has no sky), lit
//! by N finite-range point, spot and line lights, with a material per object: the scene of the
//! deferred-shading and light pre-pass studies (issues 6 and 10).
//!
//! Object 0 is the ground (room: floor, walls and ceiling); objects 1.. are buildings. Materials
//! are indexed by object id and come in three families so shading features differ across the
//! screen: plastic (coloured albedo, 4% grey specular), matte (no specular at all) and metal
//! (black albedo, coloured specular, smooth).

use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::{palette, Light, LightKind, Material, Mesh, ObjectInfo, Scene, SceneSpec, Sun};
use crate::{Camera, Result};

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let lights = r.int("lights", 64, 0, 65536)? as usize;
    let blocks = r.int("blocks", 6, 1, 64)? as usize;
    let room = r.boolean("room", false)?;
    let sun = r.boolean("sun", !room)?;
    let kinds = r.string("kinds", "mixed", &["mixed", "point", "spot", "line"])?;
    let range_scale = r.float("range", 1.0, 1e-3, 1e3)? as f32;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    r.finish()?;

    let mut rng = Pcg32::seed_from_u64(seed);
    let s = blocks as f32; // half extent of the ground: cells of 2×2 units
    let mut mesh = Mesh::default();
    let mut objects = vec![ObjectInfo {
        name: if room { "room".into() } else { "ground".into() },
        closed: room,
    }];
    let mut materials = vec![Material {
        albedo: [0.45, 0.45, 0.45],
        specular: [0.04, 0.04, 0.04],
        smoothness: 0.35,
    }];
    let ground = [0.45, 0.45, 0.45, 1.0];
    let height = 0.5 * s + 3.0;
    // Ground (and room shell): normals face the inside, where the camera is.
    push_face(
        &mut mesh,
        [
            Vec3::new(-s, 0.0, s),
            Vec3::new(s, 0.0, s),
            Vec3::new(s, 0.0, -s),
            Vec3::new(-s, 0.0, -s),
        ],
        Vec3::Y,
        ground,
        0,
    );
    if room {
        let (lo, hi) = (Vec3::new(-s, 0.0, -s), Vec3::new(s, height, s));
        push_box_faces(&mut mesh, lo, hi, -1.0, ground, 0, true);
    }
    for bx in 0..blocks {
        for bz in 0..blocks {
            let id = objects.len() as u32;
            let cx = -s + 1.0 + 2.0 * bx as f32;
            let cz = -s + 1.0 + 2.0 * bz as f32;
            let hx = rng.random_range(0.35..0.7f32);
            let hz = rng.random_range(0.35..0.7f32);
            let h = rng.random_range(0.5..(0.35 * s + 2.0));
            let fam = rng.random_range(0..4u32);
            let c = palette(id, 1.0);
            let m = match fam {
                0 => Material {
                    albedo: [0.0, 0.0, 0.0],
                    specular: [0.1 + 0.85 * c[0], 0.1 + 0.85 * c[1], 0.1 + 0.85 * c[2]],
                    smoothness: rng.random_range(0.6..0.95),
                },
                1 => Material {
                    albedo: [c[0], c[1], c[2]],
                    specular: [0.0, 0.0, 0.0],
                    smoothness: 0.0,
                },
                _ => Material {
                    albedo: [c[0], c[1], c[2]],
                    specular: [0.04, 0.04, 0.04],
                    smoothness: rng.random_range(0.1..0.8),
                },
            };
            let lo = Vec3::new(cx - hx, 0.0, cz - hz);
            let hi = Vec3::new(cx + hx, h, cz + hz);
            push_box_faces(&mut mesh, lo, hi, 1.0, [c[0], c[1], c[2], 1.0], id, false);
            objects.push(ObjectInfo {
                name: format!("building{id}"),
                closed: false,
            });
            materials.push(m);
        }
    }
    let mut out = Vec::with_capacity(lights);
    for i in 0..lights {
        let kind = match kinds.as_str() {
            "point" => LightKind::Point,
            "spot" => LightKind::Spot,
            "line" => LightKind::Line,
            _ => [LightKind::Point, LightKind::Spot, LightKind::Line][i % 3],
        };
        let c = palette(i as u32 + 7, 1.0);
        let intensity = rng.random_range(1.0..3.0f32);
        let pos = Vec3::new(
            rng.random_range(-s..s),
            rng.random_range(0.2..2.5f32),
            rng.random_range(-s..s),
        );
        let (direction, cos_outer, length) = match kind {
            LightKind::Spot => (
                Vec3::new(
                    rng.random_range(-0.6..0.6f32),
                    -1.0,
                    rng.random_range(-0.6..0.6f32),
                )
                .normalize(),
                rng.random_range(25f32..60.0).to_radians().cos(),
                0.0,
            ),
            LightKind::Line => {
                let a = rng.random_range(0.0..std::f32::consts::TAU);
                (
                    Vec3::new(a.cos(), 0.0, a.sin()),
                    -1.0,
                    rng.random_range(0.5..2.0f32),
                )
            }
            LightKind::Point => (Vec3::NEG_Y, -1.0, 0.0),
        };
        out.push(Light {
            kind,
            position: pos.into(),
            direction: direction.into(),
            color: [c[0] * intensity, c[1] * intensity, c[2] * intensity],
            range: rng.random_range(1.0..3.0f32) * range_scale,
            cos_outer,
            length,
        });
    }
    let camera = if room {
        Camera::look_at(
            DVec3::new(0.0, 0.45 * height as f64, 0.92 * s as f64),
            DVec3::new(0.0, 0.5, -0.3 * s as f64),
            60.0,
            0.05,
            6.0 * s as f64 + 10.0,
        )
    } else {
        Camera::look_at(
            DVec3::new(0.0, 0.35 * s as f64 + 1.5, 1.3 * s as f64),
            DVec3::new(0.0, 0.5, -0.2 * s as f64),
            60.0,
            0.1,
            6.0 * s as f64 + 10.0,
        )
    };
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    scene.materials = materials;
    scene.lights = out;
    scene.sun = sun.then(|| Sun {
        direction: Vec3::new(0.4, 0.8, 0.3).normalize().into(),
        color: [1.2, 1.1, 0.9],
    });
    Ok(scene)
}

/// A quad with an explicit normal (the winding does not matter: nothing culls back faces).
fn push_face(mesh: &mut Mesh, corners: [Vec3; 4], normal: Vec3, color: [f32; 4], id: u32) {
    let base = mesh.positions.len() as u32;
    for c in corners {
        mesh.positions.push(c.into());
        mesh.normals.push(normal.into());
        mesh.colors.push(color);
        mesh.object_ids.push(id);
    }
    mesh.indices
        .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
}

/// Four sides and the top (plus the bottom when `bottom`) of the box [lo, hi]; `outward` = 1
/// gives outward normals, −1 inward ones (a room seen from inside).
fn push_box_faces(
    mesh: &mut Mesh,
    lo: Vec3,
    hi: Vec3,
    outward: f32,
    color: [f32; 4],
    id: u32,
    ceiling_only: bool,
) {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let faces = [
        (
            [
                v(lo.x, hi.y, lo.z),
                v(hi.x, hi.y, lo.z),
                v(hi.x, hi.y, hi.z),
                v(lo.x, hi.y, hi.z),
            ],
            Vec3::Y,
        ),
        (
            [
                v(lo.x, lo.y, hi.z),
                v(hi.x, lo.y, hi.z),
                v(hi.x, hi.y, hi.z),
                v(lo.x, hi.y, hi.z),
            ],
            Vec3::Z,
        ),
        (
            [
                v(lo.x, lo.y, lo.z),
                v(hi.x, lo.y, lo.z),
                v(hi.x, hi.y, lo.z),
                v(lo.x, hi.y, lo.z),
            ],
            Vec3::NEG_Z,
        ),
        (
            [
                v(hi.x, lo.y, lo.z),
                v(hi.x, lo.y, hi.z),
                v(hi.x, hi.y, hi.z),
                v(hi.x, hi.y, lo.z),
            ],
            Vec3::X,
        ),
        (
            [
                v(lo.x, lo.y, lo.z),
                v(lo.x, lo.y, hi.z),
                v(lo.x, hi.y, hi.z),
                v(lo.x, hi.y, lo.z),
            ],
            Vec3::NEG_X,
        ),
    ];
    // A room's floor is the ground quad already; its shell is ceiling + walls.
    let _ = ceiling_only;
    for (corners, n) in faces {
        push_face(mesh, corners, n * outward, color, id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Params;

    #[test]
    fn city_has_lights_materials_and_sun() {
        let spec = SceneSpec::new(
            "city",
            Params::new().with("lights", crate::ParamValue::Int(40)),
        );
        let s = spec.build().unwrap();
        assert_eq!(s.lights.len(), 40);
        assert_eq!(s.materials.len(), s.objects.len());
        assert!(s.sun.is_some());
        let max_id = *s.mesh.object_ids.iter().max().unwrap() as usize;
        assert!(max_id < s.materials.len());
    }

    #[test]
    fn room_has_no_sun_by_default() {
        let spec = SceneSpec::new(
            "city",
            Params::new().with("room", crate::ParamValue::Bool(true)),
        );
        assert!(spec.build().unwrap().sun.is_none());
    }
}
