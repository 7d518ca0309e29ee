//! `slivers`: thin overlapping triangles where edges matter. `count` long triangles, each a few
//! pixels wide at most, crossing the view at random angles, at distinct depths (one slab each,
//! as `quads`, so no two intersect): nearly every covered pixel is an edge pixel of some
//! triangle, so single-sample and antialiased images differ everywhere, and per-pixel lists
//! overflow along shared edges first (the failure the issue names in the peers).

use glam::{DVec3, Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::{palette, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Camera, Result};

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let count = r.int("count", 64, 1, 1 << 20)? as u32;
    // Base width as a fraction of the view's half-extent (0.01 ≈ 1.3 px at 256²).
    let width = r.float("width", 0.01, 1e-6, 1.0)? as f32;
    let alpha = r.float("alpha", 0.5, 0.0, 1.0)? as f32;
    let span = r.float("span", 2.0, 1e-6, 1e6)?;
    let distance = r.float("distance", 4.0, 1e-3, 1e7)?;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    r.finish()?;

    let mut rng = Pcg32::seed_from_u64(seed);
    let mut mesh = Mesh::default();
    let mut objects = Vec::new();
    let fovy: f64 = 50.0;
    let half = ((fovy.to_radians() * 0.5).tan() * distance) as f32;
    let normal = [0.0, 0.0, 1.0];
    for i in 0..count {
        // Stratified depths: triangle i in its own slab, never coplanar with another.
        let t = (i as f64 + 0.25 + 0.5 * rng.random::<f64>()) / count as f64;
        let z = (span * (0.5 - t)) as f32;
        // Inside the view: centre within ±0.45, half-length ≤ 0.5 of the half-extent (a clipped
        // triangle's new vertices are a driver's own arithmetic, not the snapped inputs).
        let c = Vec2::new(
            half * rng.random_range(-0.45..0.45f32),
            half * rng.random_range(-0.45..0.45f32),
        );
        let a = rng.random_range(0.0..std::f32::consts::PI);
        let dir = Vec2::new(a.cos(), a.sin());
        let perp = Vec2::new(-dir.y, dir.x);
        let len = half * rng.random_range(0.6..1.0f32);
        let w = width * half * rng.random_range(0.5..1.5f32);
        // A needle: its tip at one end, its base (width w) at the other.
        let tip = c - dir * (0.5 * len);
        let b0 = c + dir * (0.5 * len) + perp * (0.5 * w);
        let b1 = c + dir * (0.5 * len) - perp * (0.5 * w);
        let base = mesh.positions.len() as u32;
        for p in [tip, b0, b1] {
            mesh.positions.push(Vec3::new(p.x, p.y, z).into());
            mesh.normals.push(normal);
            mesh.colors.push(palette(i, alpha));
            mesh.object_ids.push(i);
        }
        mesh.indices.extend_from_slice(&[base, base + 1, base + 2]);
        objects.push(ObjectInfo {
            name: format!("sliver{i}"),
            closed: false,
        });
    }
    let camera = Camera::look_at(
        DVec3::new(0.0, 0.0, distance),
        DVec3::ZERO,
        fovy,
        0.1,
        100.0,
    );
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use crate::{ParamValue, Params, SceneSpec};

    #[test]
    fn slivers_are_thin_deterministic_and_checked() {
        let spec = SceneSpec::new("slivers", Params::new().with("count", ParamValue::Int(20)));
        let a = spec.build().unwrap();
        let b = spec.build().unwrap();
        assert_eq!(a.mesh.triangle_count(), 20);
        assert_eq!(a.mesh.positions, b.mesh.positions, "same seed, same scene");
        // Every triangle is a needle: its area is under width × length (≪ its length²).
        let p = &a.mesh.positions;
        for t in a.mesh.indices.chunks(3) {
            let v = |i: u32| glam::Vec3::from(p[i as usize]);
            let (e1, e2) = (v(t[1]) - v(t[0]), v(t[2]) - v(t[0]));
            let area = 0.5 * e1.cross(e2).length();
            assert!(area < 0.05 * e1.length_squared(), "a needle, not a blob");
        }
        let bad = SceneSpec::new(
            "slivers",
            Params::new().with("widht", ParamValue::Float(0.1)),
        );
        assert!(bad.build().is_err(), "a misspelt parameter is an error");
        assert!(super::super::all_in_view(&a), "no triangle is clipped");
    }
}
