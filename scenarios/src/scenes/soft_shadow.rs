//! `soft_shadow`: the thesis's soft-shadow test cases (Bavoil 2007, ch. 5) — occluders over a
//! ground plane lit by a square area light straight above, framed by the light's shadow-map
//! camera. `case` picks the occluders:
//!
//! | case      | occluders                                   | what it stresses                  |
//! |-----------|---------------------------------------------|-----------------------------------|
//! | `quad`    | one square parallel to the light            | the simple case with a known bound |
//! | `spheres` | three UV spheres and a tilted torus         | closed meshes, penumbrae          |
//! | `leaves`  | many small overlapping quads                | light bleeding (hidden occluders) |
//! | `slabs`   | two thin boxes, close and parallel          | surface acne vs bias              |
//! | `tangent` | a quad nearly parallel to the light's rays  | steep depth slopes                |
//! | `obj`     | an OBJ file (`path`) normalised over the ground | a scanned mesh (bunny)       |

use std::f32::consts::{PI, TAU};
use std::path::Path;

use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::{palette, AreaLight, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{obj, Camera, Result, SceneError};

/// Half-side of the ground square; the light's frustum covers it with a 5% margin.
const GROUND: f32 = 2.5;

pub const CASES: &[&str] = &["quad", "spheres", "leaves", "slabs", "tangent", "obj"];

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let case = r.string("case", "spheres", CASES)?;
    let light_size = r.float("light_size", 1.0, 1e-3, 10.0)?;
    let light_height = r.float("light_height", 4.0, 2.5, 100.0)?;
    let segments = r.int("segments", 24, 3, 1024)? as u32;
    let leaves = r.int("leaves", 60, 1, 100_000)? as u32;
    let gap = r.float("gap", 0.05, 1e-5, 1.0)? as f32;
    let thickness = r.float("thickness", 0.02, 1e-5, 1.0)? as f32;
    let tilt_deg = r.float("tilt_deg", 2.0, 0.0, 89.0)? as f32;
    let height = r.float("height", 1.5, 0.05, 2.4)? as f32;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    let path = r.opt_string("path")?;
    if path.is_some() != (case == "obj") {
        r.problem(SceneError::OutOfRange {
            scene: label.clone(),
            param: "path".into(),
            value: path.clone().unwrap_or_default(),
            why: "case = \"obj\" needs path = \"file.obj\", and only case = \"obj\" reads one"
                .into(),
        })?;
    }
    r.finish()?;

    let mut mesh = Mesh::default();
    let mut objects = vec![ObjectInfo {
        name: "ground".into(),
        closed: false,
    }];
    let g = GROUND;
    mesh.push_quad(
        [
            Vec3::new(-g, 0.0, g),
            Vec3::new(g, 0.0, g),
            Vec3::new(g, 0.0, -g),
            Vec3::new(-g, 0.0, -g),
        ],
        [0.8, 0.8, 0.75, 1.0],
        0,
    );
    let mut add = |m: Mesh, name: &str, closed: bool| {
        mesh.append(&m);
        objects.push(ObjectInfo {
            name: name.into(),
            closed,
        });
    };
    let mut rng = Pcg32::seed_from_u64(seed);
    match case.as_str() {
        "quad" => {
            let h = 0.6;
            let mut m = Mesh::default();
            m.push_quad(
                [
                    Vec3::new(-h, height, h),
                    Vec3::new(h, height, h),
                    Vec3::new(h, height, -h),
                    Vec3::new(-h, height, -h),
                ],
                palette(1, 1.0),
                1,
            );
            add(m, "quad", false);
        }
        "spheres" => {
            let spheres = [
                (Vec3::new(-0.9, 0.6, 0.3), 0.5),
                (Vec3::new(0.5, 1.1, -0.5), 0.35),
                (Vec3::new(0.8, 0.45, 0.8), 0.4),
            ];
            for (i, (c, rad)) in spheres.into_iter().enumerate() {
                add(
                    uv_sphere(c, rad, segments, palette(i as u32 + 1, 1.0), i as u32 + 1),
                    "sphere",
                    true,
                );
            }
            add(
                torus(Vec3::new(-0.2, 1.4, -0.2), 0.6, 0.15, segments, 4),
                "torus",
                true,
            );
        }
        "leaves" => {
            // Overlapping small quads in a slab: from the light's centre the lower ones hide
            // behind the upper ones, but they still occlude part of the light from the ground.
            let mut m = Mesh::default();
            for i in 0..leaves {
                let c = Vec3::new(
                    rng.random_range(-1.2..1.2),
                    rng.random_range(0.8..1.8),
                    rng.random_range(-1.2..1.2),
                );
                let yaw = rng.random_range(0.0..TAU);
                let pitch = rng.random_range(-0.5..0.5f32);
                let s = rng.random_range(0.12..0.25f32);
                let a = Vec3::new(yaw.cos(), pitch.sin(), yaw.sin()).normalize() * s;
                let b = Vec3::new(-yaw.sin(), 0.0, yaw.cos()) * s;
                m.push_quad(
                    [c - a - b, c + a - b, c + a + b, c - a + b],
                    [0.2, 0.5 + 0.3 * (i % 3) as f32 / 2.0, 0.15, 1.0],
                    1,
                );
            }
            add(m, "leaves", false);
        }
        "slabs" => {
            // Two thin boxes `gap` apart, offset so their overlap, their own tops and the ground
            // all show: the lower top must be shadowed without the upper top acne-ing.
            let y0 = 1.0;
            add(
                boxed(
                    Vec3::new(-0.9, y0, -0.6),
                    Vec3::new(0.5, y0 + thickness, 0.6),
                    palette(1, 1.0),
                    1,
                ),
                "lower slab",
                true,
            );
            let y1 = y0 + thickness + gap;
            add(
                boxed(
                    Vec3::new(-0.4, y1, -0.8),
                    Vec3::new(1.0, y1 + thickness, 0.4),
                    palette(2, 1.0),
                    2,
                ),
                "upper slab",
                true,
            );
        }
        "tangent" => {
            // A quad containing the vertical (the light's axis) rotated by tilt_deg: from the
            // light it is a sliver whose depth changes by tens of units per texel.
            let t = tilt_deg.to_radians();
            let d = Vec3::new(t.sin(), t.cos(), 0.0);
            let base = Vec3::new(0.6, 0.05, 0.0);
            let top = base + d * 1.6;
            let w = Vec3::new(0.0, 0.0, 1.0);
            let mut m = Mesh::default();
            m.push_quad([base - w, base + w, top + w, top - w], palette(1, 1.0), 1);
            add(m, "tangent quad", false);
            add(
                uv_sphere(Vec3::new(-0.6, 0.7, 0.2), 0.4, segments, palette(2, 1.0), 2),
                "sphere",
                true,
            );
        }
        "obj" => {
            let path = path.ok_or_else(|| SceneError::OutOfRange {
                scene: label.clone(),
                param: "path".into(),
                value: String::new(),
                why: "case = \"obj\" needs path = \"file.obj\"".into(),
            })?;
            let mut m = obj::load(Path::new(&path))?;
            super::scene::normalise(&mut m);
            // Unit sphere → radius 1 resting on the ground near the centre.
            for p in &mut m.positions {
                *p = (Vec3::from(*p) + Vec3::new(0.0, 1.05, 0.0)).into();
            }
            m.colors.iter_mut().for_each(|c| *c = palette(1, 1.0));
            m.object_ids.iter_mut().for_each(|i| *i = 1);
            add(m, "obj", false);
        }
        _ => unreachable!("checked by the reader"),
    }

    let eye = DVec3::new(0.0, 3.6, 5.2);
    let camera = Camera::look_at(eye, DVec3::new(0.0, 0.4, 0.0), 45.0, 0.1, 20.0);
    let h = light_height;
    // The light looks straight down; up = −z makes its x axis world +x and its y axis world −z.
    let mut light_cam = Camera::look_at(
        DVec3::new(0.0, h, 0.0),
        DVec3::ZERO,
        2.0 * (GROUND as f64 * 1.05 / h).atan().to_degrees(),
        0.1 * h,
        2.0 * h,
    );
    light_cam.up = [0.0, 0.0, -1.0];
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    scene.area_light = Some(AreaLight {
        camera: light_cam,
        size: light_size,
    });
    Ok(scene)
}

/// A UV sphere (closed) of `seg` segments around and seg/2 rings.
pub fn uv_sphere(c: Vec3, r: f32, seg: u32, color: [f32; 4], id: u32) -> Mesh {
    let rings = (seg / 2).max(2);
    let mut m = Mesh::default();
    for i in 0..=rings {
        let th = PI * i as f32 / rings as f32;
        for j in 0..=seg {
            let ph = TAU * j as f32 / seg as f32;
            let n = Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin());
            m.positions.push((c + n * r).into());
            m.normals.push(n.into());
            m.colors.push(color);
            m.object_ids.push(id);
        }
    }
    grid_indices(&mut m, rings, seg);
    m
}

/// A torus around the y axis tilted by 30° about x (closed).
pub fn torus(c: Vec3, big: f32, small: f32, seg: u32, id: u32) -> Mesh {
    let rot = glam::Quat::from_rotation_x(0.5);
    let color = palette(id, 1.0);
    let mut m = Mesh::default();
    let minor = (seg / 2).max(3);
    for i in 0..=seg {
        let u = TAU * i as f32 / seg as f32;
        for j in 0..=minor {
            let v = TAU * j as f32 / minor as f32;
            let n = Vec3::new(v.cos() * u.cos(), v.sin(), v.cos() * u.sin());
            let ring = Vec3::new(u.cos(), 0.0, u.sin()) * big;
            m.positions.push((c + rot * (ring + n * small)).into());
            m.normals.push((rot * n).into());
            m.colors.push(color);
            m.object_ids.push(id);
        }
    }
    grid_indices(&mut m, seg, minor);
    m
}

/// Two triangles per cell of a (rows+1)×(cols+1) vertex grid.
fn grid_indices(m: &mut Mesh, rows: u32, cols: u32) {
    let w = cols + 1;
    for i in 0..rows {
        for j in 0..cols {
            let a = i * w + j;
            m.indices
                .extend_from_slice(&[a, a + w, a + 1, a + 1, a + w, a + w + 1]);
        }
    }
}

/// An axis-aligned box (closed), 12 triangles.
pub fn boxed(lo: Vec3, hi: Vec3, color: [f32; 4], id: u32) -> Mesh {
    let mut m = Mesh::default();
    let p = |x: bool, y: bool, z: bool| {
        Vec3::new(
            if x { hi.x } else { lo.x },
            if y { hi.y } else { lo.y },
            if z { hi.z } else { lo.z },
        )
    };
    let (f, t) = (false, true);
    for q in [
        [p(f, t, t), p(t, t, t), p(t, t, f), p(f, t, f)],
        [p(f, f, f), p(t, f, f), p(t, f, t), p(f, f, t)],
        [p(f, f, t), p(t, f, t), p(t, t, t), p(f, t, t)],
        [p(t, f, f), p(f, f, f), p(f, t, f), p(t, t, f)],
        [p(t, f, t), p(t, f, f), p(t, t, f), p(t, t, t)],
        [p(f, f, f), p(f, f, t), p(f, t, t), p(f, t, f)],
    ] {
        m.push_quad(q, color, id);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ParamValue, Params};

    #[test]
    fn every_case_builds_with_its_light_and_valid_mesh() {
        for case in CASES.iter().filter(|c| **c != "obj") {
            let spec = SceneSpec::new(
                "soft_shadow",
                Params::new().with("case", ParamValue::Str(case.to_string())),
            );
            let s = spec.build().unwrap();
            let l = s.area_light.as_ref().expect("light");
            assert!(l.size > 0.0, "{case}");
            assert!(s.mesh.triangle_count() > 2, "{case}");
        }
    }

    #[test]
    fn obj_case_without_path_is_a_clear_error() {
        let spec = SceneSpec::new(
            "soft_shadow",
            Params::new().with("case", ParamValue::Str("obj".into())),
        );
        let e = spec.build().unwrap_err().to_string();
        assert!(e.contains("path"), "{e}");
    }
}
