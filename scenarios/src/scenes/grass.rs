//! `grass`: the thesis's benchmark (Bavoil 2007, ch. 3–4): N blades of grass, 5 triangles each
//! (a strip of 7 vertices), scattered over a patch and seen from above at an angle.

use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::{Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Camera, Result};

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let blades = r.int("blades", 2000, 1, 20_000_000)? as u32;
    let alpha = r.float("alpha", 0.5, 0.0, 1.0)? as f32;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    r.finish()?;

    let mut rng = Pcg32::seed_from_u64(seed);
    let mut mesh = Mesh::default();
    mesh.positions.reserve(blades as usize * 7);
    // Patch side grows with sqrt(N) so density (and depth complexity) stays about constant.
    let side = (blades as f32).sqrt() * 0.08;
    for _ in 0..blades {
        let base = Vec3::new(
            rng.random_range(-side..side),
            0.0,
            rng.random_range(-side..side),
        );
        let angle = rng.random_range(0.0..std::f32::consts::TAU);
        let dir = Vec3::new(angle.cos(), 0.0, angle.sin());
        let bend = Vec3::new(
            rng.random_range(-0.3..0.3),
            0.0,
            rng.random_range(-0.3..0.3),
        );
        let height = rng.random_range(0.6..1.2f32);
        let width = 0.05;
        let shade = rng.random_range(0.5..1.0f32);
        let color = [0.2 * shade, 0.55 + 0.4 * shade, 0.15, alpha];
        let first = mesh.positions.len() as u32;
        // 7 vertices: 3 pairs narrowing upward and a tip; strip order gives 5 triangles.
        for k in 0..7u32 {
            let level = (k / 2) as f32 / 3.0;
            let t = if k == 6 { 1.0 } else { level };
            let half = if k == 6 { 0.0 } else { width * (1.0 - level) };
            let side_sign = if k % 2 == 0 { -1.0 } else { 1.0 };
            let p = base + dir * (half * side_sign) + Vec3::Y * (height * t) + bend * (t * t);
            mesh.positions.push(p.into());
            mesh.normals.push(dir.cross(Vec3::Y).normalize().into());
            mesh.colors.push(color);
            mesh.object_ids.push(0);
        }
        for k in 0..5u32 {
            let (a, bb, c) = if k % 2 == 0 {
                (k, k + 1, k + 2)
            } else {
                (k + 1, k, k + 2)
            };
            mesh.indices
                .extend_from_slice(&[first + a, first + bb, first + c]);
        }
    }
    let eye = DVec3::new(0.0, side as f64 * 1.1 + 1.5, side as f64 * 1.6 + 2.0);
    // Near plane at 15% of the eye distance (in front of the nearest blade): depth precision
    // for the patch, not for empty space in front of the camera.
    let near = eye.length() * 0.15;
    let camera = Camera::look_at(
        eye,
        DVec3::new(0.0, 0.3, 0.0),
        50.0,
        near,
        eye.length() * 4.0,
    );
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = vec![ObjectInfo {
        name: "grass".into(),
        closed: false,
    }];
    Ok(scene)
}
