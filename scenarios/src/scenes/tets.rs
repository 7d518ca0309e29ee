//! `tets`: the faces of a tetrahedral mesh carrying a scalar field, for the thesis's §6.3
//! sorting-and-blending applications (Fig. 6.4: isosurfaces and volume rendering of unstructured
//! grids through the k-buffer). A cube [-1, 1]³ of `cells`³ cells, each split into six
//! tetrahedra along its main diagonal (Freudenthal–Kuhn: the split of every cube face agrees
//! with its neighbour's, so the mesh is conforming). Every distinct triangle is emitted once
//! (a face shared by two tetrahedra is one triangle, as §6.3's ray gaps need: consecutive
//! fragments along a ray then bound exactly one tetrahedron's segment).
//!
//! The scalar s ∈ [0, 1] of an analytic field (two Gaussian blobs) sits at the vertices and is
//! carried in the colour's red channel (and green and blue: a grey ramp), alpha = `alpha` for
//! the other effects. Interpolated over a face it is the tetrahedra's piecewise-linear field on
//! that face, so along a ray between two consecutive fragments it is linear in depth: what the
//! `volume` and `isosurface` effects integrate and cut. Boundary faces face outward; interior
//! faces face out of the first tetrahedron that names them.

use std::collections::HashMap;

use glam::{DVec3, Vec3};

use super::{Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Camera, Result};

/// The field at `p` ∈ [-1, 1]³: two Gaussian blobs, in [0, 1).
pub fn field(p: Vec3) -> f32 {
    let a = (p - Vec3::new(-0.3, 0.2, -0.1)).length_squared();
    let b = (p - Vec3::new(0.45, -0.35, 0.3)).length_squared();
    0.6 * (-a / 0.35).exp() + 0.38 * (-b / 0.15).exp()
}

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let cells = r.int("cells", 4, 1, 32)? as usize;
    let alpha = r.float("alpha", 0.2, 0.0, 1.0)? as f32;
    // Distance of the eye from the cube's centre, along a generic diagonal (no face, edge or
    // vertex of the grid lines up with the view, so pixel centres rarely sit on a shared edge).
    let distance = r.float("distance", 4.5, 2.0, 1e4)?;
    r.finish()?;

    let n = cells + 1;
    let vid = |i: usize, j: usize, k: usize| (i + n * (j + n * k)) as u32;
    let mut mesh = Mesh::default();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = Vec3::new(i as f32, j as f32, k as f32) * (2.0 / cells as f32) - 1.0;
                let s = field(p);
                mesh.positions.push(p.into());
                mesh.colors.push([s, s, s, alpha]);
                mesh.object_ids.push(0);
            }
        }
    }
    // Six tetrahedra per cell: 000 → e_a → e_a + e_b → 111 for each order (a, b, c) of the axes.
    const ORDERS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut faces: HashMap<[u32; 3], [u32; 3]> = HashMap::new();
    let mut order: Vec<[u32; 3]> = Vec::new();
    for k in 0..cells {
        for j in 0..cells {
            for i in 0..cells {
                for axes in ORDERS {
                    let mut c = [i, j, k];
                    let mut tet = [vid(c[0], c[1], c[2]); 4];
                    for (step, &a) in axes.iter().enumerate() {
                        c[a] += 1;
                        tet[step + 1] = vid(c[0], c[1], c[2]);
                    }
                    for skip in 0..4 {
                        let f: Vec<u32> = (0..4).filter(|&v| v != skip).map(|v| tet[v]).collect();
                        let mut key = [f[0], f[1], f[2]];
                        key.sort_unstable();
                        if faces.contains_key(&key) {
                            continue;
                        }
                        // Wound outward from this tetrahedron: away from the vertex it skips.
                        let pos = |v: u32| Vec3::from(mesh.positions[v as usize]);
                        let (a, b, cc) = (pos(f[0]), pos(f[1]), pos(f[2]));
                        let outward = (b - a).cross(cc - a).dot(a - pos(tet[skip])) > 0.0;
                        let tri = if outward {
                            [f[0], f[1], f[2]]
                        } else {
                            [f[0], f[2], f[1]]
                        };
                        faces.insert(key, tri);
                        order.push(tri);
                    }
                }
            }
        }
    }
    // Vertex normals: the field's direction of decrease (the isosurface's outward normal), so
    // an effect reading normals gets something defined; §6.3 reads none.
    mesh.normals = mesh
        .positions
        .iter()
        .map(|&p| {
            let p = Vec3::from(p);
            let h = 1e-3;
            let g = Vec3::new(
                field(p + Vec3::X * h) - field(p - Vec3::X * h),
                field(p + Vec3::Y * h) - field(p - Vec3::Y * h),
                field(p + Vec3::Z * h) - field(p - Vec3::Z * h),
            );
            (-g).normalize_or(Vec3::Z).into()
        })
        .collect();
    mesh.indices = order.into_iter().flatten().collect();
    let eye = DVec3::new(0.62, 0.48, 0.85).normalize() * distance;
    let camera = Camera::look_at(eye, DVec3::ZERO, 45.0, 0.1, 100.0);
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = vec![ObjectInfo {
        name: "tetrahedra".into(),
        closed: false,
    }];
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ParamValue, Params};

    fn build(cells: i64) -> Scene {
        SceneSpec::new("tets", Params::new().with("cells", ParamValue::Int(cells)))
            .build()
            .unwrap()
    }

    #[test]
    fn every_face_of_the_conforming_mesh_is_emitted_once() {
        // n³ cells × 6 tetrahedra; each interior face is shared by two, each boundary face (two
        // triangles per cell face on the surface: 6·2·n²) belongs to one: F = (4T + B) / 2.
        for n in [1usize, 2, 3] {
            let s = build(n as i64);
            let (t, b) = (6 * n * n * n, 12 * n * n);
            assert_eq!(s.mesh.triangle_count(), (4 * t + b) / 2, "cells = {n}");
            let mut seen = std::collections::HashSet::new();
            for tri in s.mesh.indices.chunks(3) {
                let mut k = [tri[0], tri[1], tri[2]];
                k.sort_unstable();
                assert!(seen.insert(k), "face {k:?} twice");
            }
            assert!(super::super::all_in_view(&s));
        }
    }

    #[test]
    fn the_scalar_is_the_field_in_the_red_channel_and_in_range() {
        let s = build(3);
        for (p, c) in s.mesh.positions.iter().zip(&s.mesh.colors) {
            assert_eq!(c[0], field(Vec3::from(*p)));
            assert!((0.0..1.0).contains(&c[0]));
        }
        let hi = s.mesh.colors.iter().map(|c| c[0]).fold(0.0, f32::max);
        assert!(
            hi > 0.4,
            "the field reaches the iso-values the suite cuts: {hi}"
        );
    }
}
