//! `hair`: many thin, long, curved ribbons (hair cards) hanging from a scalp, seen from the
//! front: every pixel of the hair crosses strands of the front and of the back, a few dozen thin
//! layers of moderate opacity whose order changes pixel to pixel (the case where k-buffers,
//! MLAB and adaptive transparency truncate or merge, and WBOIT's weights blur the layers).
//!
//! Each strand's root lies on a spherical cap (an invisible head of radius 0.42 at y = 0.7);
//! its centre line leaves the scalp outward, falls with gravity and waves sideways:
//! p(t) = root + out·0.25·L·t·(1 − t/2) − y·0.9·L·t^1.3 + side·0.04·L·t·sin(2π·w·t + φ),
//! t ∈ [0, 1], L = length·U(0.75, 1.25). The ribbon at each of the `segments + 1` samples is
//! offset ±width/2 (tapering to 40 % at the tip) along tangent × (eye − p), so it faces the
//! camera. Strands may cross each other (ribbon intersections, as real hair does); none are
//! coplanar by construction.

use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::{palette, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Camera, Result};

/// Centre and radius of the (invisible) head the strands grow from.
const HEAD: Vec3 = Vec3::new(0.0, 0.7, 0.0);
const SCALP: f32 = 0.42;

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let strands = r.int("strands", 3000, 1, 2_000_000)? as u32;
    let segments = r.int("segments", 8, 1, 256)? as u32;
    // Ribbon width at the root, world units (the head is 0.84 wide).
    let width = r.float("width", 0.012, 1e-5, 1.0)? as f32;
    let length = r.float("length", 1.6, 0.05, 10.0)? as f32;
    let alpha = r.float("alpha", 0.3, 0.0, 1.0)? as f32;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    r.finish()?;

    let camera = frame(length);
    let eye = DVec3::from(camera.eye).as_vec3();
    let mut rng = Pcg32::seed_from_u64(seed);
    let mut mesh = Mesh::default();
    let per_strand = (segments as usize + 1) * 2;
    mesh.positions.reserve(strands as usize * per_strand);
    let mut objects = Vec::with_capacity(strands as usize);
    let mut centre = vec![Vec3::ZERO; segments as usize + 1];
    for s in 0..strands {
        // Roots on the cap cos θ ∈ [−0.35, 1] (θ from +y): top, sides and back of the head.
        let cos_t: f32 = rng.random_range(-0.35..1.0);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi: f32 = rng.random_range(0.0..std::f32::consts::TAU);
        let dir = Vec3::new(sin_t * phi.cos(), cos_t, sin_t * phi.sin());
        let root = HEAD + dir * SCALP;
        // Horizontal outward direction (the azimuth's, also for roots at the crown).
        let out = Vec3::new(phi.cos(), 0.0, phi.sin());
        let side = Vec3::Y.cross(out);
        let len = length * rng.random_range(0.75..1.25f32);
        let waves: f32 = rng.random_range(0.8..2.0);
        let phase: f32 = rng.random_range(0.0..std::f32::consts::TAU);
        for (j, p) in centre.iter_mut().enumerate() {
            let t = j as f32 / segments as f32;
            *p = root + out * (0.25 * len * t * (1.0 - 0.5 * t))
                - Vec3::Y * (0.9 * len * t.powf(1.3))
                + side * (0.04 * len * t * (std::f32::consts::TAU * waves * t + phase).sin());
        }
        let color = palette(s, alpha);
        let first = mesh.positions.len() as u32;
        for j in 0..=segments as usize {
            let t = j as f32 / segments as f32;
            let tangent = centre[(j + 1).min(segments as usize)] - centre[j.saturating_sub(1)];
            let across = tangent.cross(eye - centre[j]).normalize_or(Vec3::X);
            let normal = across.cross(tangent).normalize_or(Vec3::Z);
            let half = 0.5 * width * (1.0 - 0.6 * t);
            for p in [centre[j] - across * half, centre[j] + across * half] {
                mesh.positions.push(p.into());
                mesh.normals.push(normal.into());
                mesh.colors.push(color);
                mesh.object_ids.push(s);
            }
        }
        for j in 0..segments {
            let (a0, b0, a1, b1) = (
                first + 2 * j,
                first + 2 * j + 1,
                first + 2 * j + 2,
                first + 2 * j + 3,
            );
            mesh.indices.extend_from_slice(&[a0, b0, a1, b0, b1, a1]);
        }
        objects.push(ObjectInfo {
            name: format!("strand{s}"),
            closed: false,
        });
    }
    let mut scene = Scene::new(spec.clone(), mesh, camera);
    scene.objects = objects;
    Ok(scene)
}

/// A camera on +z framing the hair of strands up to 1.25·`length` long: y from the crown
/// (HEAD.y + SCALP) down to the lowest root minus the longest fall, the horizontal distance from
/// the y axis within the scalp plus the outward sweep and the wave.
fn frame(length: f32) -> Camera {
    let top = (HEAD.y + SCALP) as f64;
    let bottom = (HEAD.y - 0.35 * SCALP - 0.9 * 1.25 * length) as f64;
    let half_width = (SCALP + (0.125 + 0.04) * 1.25 * length) as f64;
    // Every point is within half_width of the y axis horizontally: a bounding sphere.
    let radius = (0.5 * (top - bottom)).hypot(half_width);
    let centre = DVec3::new(0.0, 0.5 * (top + bottom), 0.0);
    let fovy: f64 = 45.0;
    let dist = radius / (fovy.to_radians() * 0.5).sin() * 1.05;
    Camera::look_at(
        centre + DVec3::new(0.0, 0.0, dist),
        centre,
        fovy,
        dist * 0.05,
        dist * 4.0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ParamValue, Params};

    fn build(params: Params) -> Result<Scene> {
        SceneSpec::new("hair", params).build()
    }

    #[test]
    fn hair_is_deterministic_with_two_triangles_per_segment() {
        let p = Params::new()
            .with("strands", ParamValue::Int(500))
            .with("segments", ParamValue::Int(6));
        let a = build(p.clone()).unwrap();
        let b = build(p).unwrap();
        assert_eq!(a.mesh.positions, b.mesh.positions);
        assert_eq!(a.mesh.triangle_count(), 500 * 6 * 2);
        assert_eq!(a.mesh.vertex_count(), 500 * 7 * 2);
        assert_eq!(a.objects.len(), 500);
        assert_eq!(
            build(Params::new()).unwrap().mesh.triangle_count(),
            3000 * 8 * 2
        );
    }

    #[test]
    fn hair_ribbons_have_the_requested_width_and_fit_the_view() {
        let s = build(Params::new().with("width", ParamValue::Float(0.02))).unwrap();
        // The two vertices of each sample are `width` apart at the root, 40 % of it at the tip.
        let v = &s.mesh.positions;
        let w0 = (Vec3::from(v[1]) - Vec3::from(v[0])).length();
        let tip = 2 * 8;
        let w1 = (Vec3::from(v[tip + 1]) - Vec3::from(v[tip])).length();
        assert!(
            (w0 - 0.02).abs() < 1e-6 && (w1 - 0.008).abs() < 1e-6,
            "{w0} {w1}"
        );
        for length in [0.3, 1.6, 4.0] {
            let s = build(Params::new().with("length", ParamValue::Float(length))).unwrap();
            assert!(
                super::super::all_in_view(&s),
                "length {length}: hair leaves the view"
            );
        }
    }

    #[test]
    fn hair_bad_params_are_errors() {
        let e = build(Params::new().with("segments", ParamValue::Int(0)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("segments") && e.contains("out of range"), "{e}");
        let e = build(Params::new().with("alpha", ParamValue::Float(1.5)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("alpha"), "{e}");
        let e = build(Params::new().with("strand", ParamValue::Int(3)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown parameter 'strand'"), "{e}");
    }
}
