//! `quads`: d screen-parallel quads, each covering the image centre, at distinct depths, so the
//! maximum depth complexity is exactly d (at the centre pixel) and layers never touch.

use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::{palette, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Camera, Result};

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let d = r.int("depth_complexity", 8, 1, 4096)? as u32;
    let alpha = r.float("alpha", 0.35, 0.0, 1.0)? as f32;
    let tilt = r.float("tilt", 0.0, 0.0, 0.5)? as f32;
    // Depth span of the stack (world units along the view axis); small spans stress precision.
    let span = r.float("span", 2.0, 1e-6, 1e6)?;
    let distance = r.float("distance", 4.0, 1e-3, 1e7)?;
    let near = r.float("near", 0.1, 1e-7, 1e6)?;
    let far = r.float("far", 100.0, 1e-6, 1e12)?;
    let reversed_z = r.boolean("reversed_z", false)?;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    r.finish()?;

    let mut rng = Pcg32::seed_from_u64(seed);
    let mut mesh = Mesh::default();
    let mut objects = Vec::new();
    // Half-extent of the view at the stack's centre: quads span 20–95% of it around the centre.
    let fovy: f64 = 50.0;
    let half = ((fovy.to_radians() * 0.5).tan() * distance) as f32;
    for i in 0..d {
        // Stratified depths: layer i sits in its own slab, so no two quads are coplanar.
        let t = (i as f64 + 0.25 + 0.5 * rng.random::<f64>()) / d as f64;
        let z = (span * (0.5 - t)) as f32;
        let lo = Vec3::new(
            -half * rng.random_range(0.2..0.95),
            -half * rng.random_range(0.2..0.95),
            z,
        );
        let hi = Vec3::new(
            half * rng.random_range(0.2..0.95),
            half * rng.random_range(0.2..0.95),
            z,
        );
        // A tilt about x keeps the centre on the quad (depth changes across it, slabs may cross).
        let slope = tilt * rng.random_range(-1.0..1.0f32);
        let zc = |y: f32| z + slope * y * (span as f32 / d as f32);
        let corners = [
            Vec3::new(lo.x, lo.y, zc(lo.y)),
            Vec3::new(hi.x, lo.y, zc(lo.y)),
            Vec3::new(hi.x, hi.y, zc(hi.y)),
            Vec3::new(lo.x, hi.y, zc(hi.y)),
        ];
        mesh.push_quad(corners, palette(i, alpha), i);
        objects.push(ObjectInfo {
            name: format!("quad{i}"),
            closed: false,
        });
    }
    let mut camera = Camera::look_at(DVec3::new(0.0, 0.0, distance), DVec3::ZERO, fovy, near, far);
    camera.reversed_z = reversed_z;
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    // Every quad covers the centre; with tilt the slabs may cross but coverage is unchanged.
    scene.analytic_max_depth_complexity = Some(d);
    Ok(scene)
}
