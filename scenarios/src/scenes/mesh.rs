//! `mesh`: a procedural large mesh for the geometry-feeding study (Bavoil 2007, ch. 3): one
//! connected, closed, smoothly shaded surface of about `triangles` triangles with shared
//! vertices (≈ 2 triangles per vertex, like a scanned model), in a cache-friendly original
//! order (row by row), so vertex-cache reuse, batching and index precision behave as on real
//! meshes.
//!
//! `shape = "sphere"` (default) is a bumpy latitude–longitude sphere with poles; `"grid"` is a
//! wavy height field seen from above at an angle (an open surface, no poles).

use glam::{DVec3, Vec3};

use super::{frame_sphere, palette, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Camera, Result};

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let triangles = r.int("triangles", 20_000, 8, 200_000_000)? as u64;
    let shape = r.string("shape", "sphere", &["sphere", "grid"])?;
    let alpha = r.float("alpha", 1.0, 0.0, 1.0)? as f32;
    r.finish()?;

    // rows × cols quads, two triangles each; cols ≈ 2·rows keeps the quads about square on the sphere.
    let rows = (((triangles as f64) / 4.0).sqrt().round() as u32).max(2);
    let cols = ((triangles as f64 / (2.0 * rows as f64)).round() as u32).max(3);
    let mut mesh = Mesh::default();
    let (nv_rows, nv_cols) = (rows + 1, cols + 1);
    let nverts = (nv_rows * nv_cols) as usize;
    mesh.positions.reserve(nverts);
    mesh.normals.reserve(nverts);
    mesh.colors.reserve(nverts);
    mesh.object_ids.reserve(nverts);
    let sphere = shape == "sphere";
    for i in 0..nv_rows {
        for j in 0..nv_cols {
            let u = j as f32 / cols as f32;
            let v = i as f32 / rows as f32;
            let (p, n) = if sphere {
                let theta = v * std::f32::consts::PI;
                let phi = u * std::f32::consts::TAU;
                let dir = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                // Low-frequency bumps so normals vary; radius stays in [0.9, 1.0].
                let bump = 0.95 + 0.05 * (5.0 * phi).sin() * (4.0 * theta).sin();
                (dir * bump, dir)
            } else {
                let x = u * 2.0 - 1.0;
                let z = v * 2.0 - 1.0;
                let h = 0.1 * (6.0 * x).sin() * (5.0 * z).cos();
                let dhdx = 0.6 * (6.0 * x).cos() * (5.0 * z).cos();
                let dhdz = -0.5 * (6.0 * x).sin() * (5.0 * z).sin();
                (Vec3::new(x, h, z), Vec3::new(-dhdx, 1.0, -dhdz).normalize())
            };
            mesh.positions.push(p.into());
            mesh.normals.push(n.into());
            let mut c = palette((i / 8) * 7 + j / 8, alpha);
            c[0] = (c[0] * (0.75 + 0.25 * u)).min(1.0);
            mesh.colors.push(c);
            mesh.object_ids.push(0);
        }
    }
    mesh.indices.reserve(rows as usize * cols as usize * 6);
    for i in 0..rows {
        for j in 0..cols {
            let a = i * nv_cols + j;
            let b = a + 1;
            let c = a + nv_cols;
            let d = c + 1;
            mesh.indices.extend_from_slice(&[a, c, b, b, c, d]);
        }
    }
    let camera = if sphere {
        frame_sphere(1.0, 45.0)
    } else {
        Camera::look_at(
            DVec3::new(0.0, 1.6, 1.9),
            DVec3::new(0.0, 0.0, 0.0),
            45.0,
            0.1,
            10.0,
        )
    };
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = vec![ObjectInfo {
        name: shape,
        closed: sphere,
    }];
    Ok(scene)
}
