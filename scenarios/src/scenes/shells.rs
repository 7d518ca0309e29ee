//! `shells`: n nested closed spheres or boxes centred on the view axis. A ray through the image
//! centre crosses every shell twice, so the maximum depth complexity is 2n.

use glam::Vec3;

use super::{frame_sphere, palette, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::Result;

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let count = r.int("count", 4, 1, 512)? as u32;
    let shape = r.string("shape", "sphere", &["sphere", "box"])?;
    let segments = r.int("segments", 24, 3, 2048)? as u32;
    let alpha = r.float("alpha", 0.3, 0.0, 1.0)? as f32;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u32;
    r.finish()?;

    let mut mesh = Mesh::default();
    let mut objects = Vec::new();
    for i in 0..count {
        // Radii from 1.0 down to 0.3, evenly spaced: shells never touch.
        let radius = 1.0 - 0.7 * i as f32 / count.max(2) as f32;
        let color = palette(i + seed, alpha);
        let shell = if shape == "sphere" {
            sphere(radius, segments, color, i)
        } else {
            cube(radius, color, i)
        };
        mesh.append(&shell);
        objects.push(ObjectInfo {
            name: format!("{shape}{i}"),
            closed: true,
        });
    }
    let mut scene = Scene::new(spec.clone(), mesh, frame_sphere(1.0, 45.0));
    scene.objects = objects;
    scene.analytic_max_depth_complexity = Some(2 * count);
    Ok(scene)
}

/// UV sphere with `seg` segments around and `seg/2` rings, outward normals.
pub fn sphere(radius: f32, seg: u32, color: [f32; 4], id: u32) -> Mesh {
    let rings = (seg / 2).max(2);
    let mut m = Mesh::default();
    for j in 0..=rings {
        let v = std::f32::consts::PI * j as f32 / rings as f32;
        for i in 0..=seg {
            let u = std::f32::consts::TAU * i as f32 / seg as f32;
            // Slightly rotated about the view axis so no silhouette edge passes a pixel centre exactly.
            let n = Vec3::new(
                v.sin() * (u + 0.013).cos(),
                v.cos(),
                v.sin() * (u + 0.013).sin(),
            );
            m.positions.push((n * radius).into());
            m.normals.push(n.into());
            m.colors.push(color);
            m.object_ids.push(id);
        }
    }
    let row = seg + 1;
    for j in 0..rings {
        for i in 0..seg {
            let a = j * row + i;
            let b = a + row;
            // Counter-clockwise seen from outside (front faces outward); skip the pole degenerates.
            if j != 0 {
                m.indices.extend_from_slice(&[a, a + 1, b]);
            }
            if j != rings - 1 {
                m.indices.extend_from_slice(&[a + 1, b + 1, b]);
            }
        }
    }
    m
}

/// Axis-aligned cube of half-size `h` (rotated a little so faces are not edge-on).
pub fn cube(h: f32, color: [f32; 4], id: u32) -> Mesh {
    let rot = glam::Quat::from_euler(glam::EulerRot::YXZ, 0.5, 0.35, 0.0);
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
        let c = n * h;
        let corners = [
            c - a * h - b * h,
            c + a * h - b * h,
            c + a * h + b * h,
            c - a * h + b * h,
        ]
        .map(|p| rot * p);
        m.push_quad(corners, color, id);
    }
    m
}
