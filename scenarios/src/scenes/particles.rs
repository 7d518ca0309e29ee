//! `particles`: N camera-facing quads of low opacity in a smoke column, the case where per-pixel
//! depth complexity runs into the hundreds and every fragment matters a little (the regime
//! moment-based OIT and MLAB were designed for; Münstermann et al. 2018, Salvi & Vaidyanathan
//! 2014).
//!
//! Layout: the column stands on the view's y axis. Heights are uniform in ±1.2·spread, the
//! horizontal offset x is Gaussian (clamped at 3σ) with a σ that widens with height (a plume),
//! and depth is
//! stratified: particle i gets its own slot of the column's depth span (slot width
//! 2·spread/count, position jittered inside the middle half), so no two quads share a depth: at
//! the defaults any two differ by ≥ 1e-4 world units, over 10 f32 steps of window depth
//! (checked in reference/tests/continuum_scenes.rs), so a GPU method comparing f32 depths can
//! always order them. Quads are parallel to the image plane (the camera looks down −z), so each
//! has one view depth.
//!
//! Expected centre coverage ≈ count · E[side²] / (2.4·spread · √(2π)·σ(0)) with σ(0) =
//! 0.3125·spread: ≈ 0.0224·count at the defaults, i.e. ≈ 220 layers at the centre pixel.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use super::{frame_sphere, palette, Mesh, ObjectInfo, Scene, SceneSpec};
use crate::{Result, SceneError};

pub fn build(spec: &SceneSpec) -> Result<Scene> {
    let label = spec.label();
    let mut r = spec.params.reader(&label);
    let count = r.int("count", 10_000, 1, 4_000_000)? as u32;
    let alpha_min = r.float("alpha_min", 0.02, 0.0, 1.0)?;
    let alpha_max = r.float("alpha_max", 0.3, 0.0, 1.0)?;
    // Mean side length of a quad (sides vary ±40 % around it), world units.
    let size = r.float("size", 0.2, 1e-4, 10.0)? as f32;
    // Half-width scale of the column (its height is ±1.2·spread), world units.
    let spread = r.float("spread", 1.0, 1e-2, 100.0)? as f32;
    let seed = r.int("seed", 1, 0, i64::MAX)? as u64;
    r.finish()?;
    if alpha_min > alpha_max {
        return Err(SceneError::OutOfRange {
            scene: label,
            param: "alpha_min".into(),
            value: alpha_min.to_string(),
            why: format!("must not exceed alpha_max = {alpha_max}"),
        });
    }

    let mut rng = Pcg32::seed_from_u64(seed);
    // A random permutation assigns depth slots, so depth is independent of height and x.
    let mut slots: Vec<u32> = (0..count).collect();
    for i in (1..slots.len()).rev() {
        slots.swap(i, rng.random_range(0..=i));
    }
    let half_height = 1.2 * spread;
    let mut mesh = Mesh::default();
    mesh.positions.reserve(count as usize * 4);
    let mut objects = Vec::with_capacity(count as usize);
    for (i, &slot) in slots.iter().enumerate() {
        let y = rng.random_range(-half_height..half_height);
        // The plume widens upward: σ from 0.25·spread at the bottom to 0.375·spread at the top.
        let t = (y + half_height) / (2.0 * half_height);
        let sigma = 0.25 * spread * (1.0 + 0.5 * t);
        let x = sigma * gaussian(&mut rng).clamp(-3.0, 3.0);
        let z =
            spread * (1.0 - 2.0 * (slot as f32 + 0.25 + 0.5 * rng.random::<f32>()) / count as f32);
        let h = 0.5 * size * rng.random_range(0.6..1.4f32);
        let alpha = rng.random_range(alpha_min..=alpha_max) as f32;
        let c = Vec3::new(x, y, z);
        let corners = [
            c + Vec3::new(-h, -h, 0.0),
            c + Vec3::new(h, -h, 0.0),
            c + Vec3::new(h, h, 0.0),
            c + Vec3::new(-h, h, 0.0),
        ];
        mesh.push_quad(corners, palette(i as u32, alpha), i as u32);
        objects.push(ObjectInfo {
            name: format!("particle{i}"),
            closed: false,
        });
    }
    // Frames the whole column: a sphere through its farthest corner.
    let radius = mesh
        .positions
        .iter()
        .map(|p| Vec3::from(*p).length())
        .fold(0.0f32, f32::max) as f64;
    let mut scene = Scene::new(spec.clone(), mesh, frame_sphere(radius, 45.0));
    scene.objects = objects;
    Ok(scene)
}

/// A standard normal sample (Box–Muller), from two uniforms of `rng`.
pub(crate) fn gaussian(rng: &mut Pcg32) -> f32 {
    let u1: f32 = rng.random_range(f32::EPSILON..1.0);
    let u2: f32 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ParamValue, Params};

    fn build(params: Params) -> Result<Scene> {
        SceneSpec::new("particles", params).build()
    }

    #[test]
    fn particles_default_is_deterministic_with_two_triangles_each() {
        let a = build(Params::new()).unwrap();
        let b = build(Params::new()).unwrap();
        assert_eq!(a.mesh.positions, b.mesh.positions);
        assert_eq!(a.mesh.colors, b.mesh.colors);
        assert_eq!(a.mesh.triangle_count(), 2 * 10_000);
        assert_eq!(a.objects.len(), 10_000);
        let c = build(Params::new().with("seed", ParamValue::Int(2))).unwrap();
        assert_ne!(
            a.mesh.positions, c.mesh.positions,
            "the seed changes the cloud"
        );
        assert!(
            super::super::all_in_view(&a),
            "the camera frames the column"
        );
    }

    #[test]
    fn particles_alpha_stays_in_its_range_and_depths_are_distinct() {
        let p = Params::new()
            .with("count", ParamValue::Int(3000))
            .with("alpha_min", ParamValue::Float(0.1))
            .with("alpha_max", ParamValue::Float(0.2));
        let s = build(p).unwrap();
        assert!(s.mesh.colors.iter().all(|c| (0.1..=0.2).contains(&c[3])));
        // One z per quad (screen-parallel), all distinct and at least a slot quarter apart.
        let mut z: Vec<f32> = s.mesh.positions.chunks(4).map(|q| q[0][2]).collect();
        assert!(s
            .mesh
            .positions
            .chunks(4)
            .all(|q| q.iter().all(|p| p[2] == q[0][2])));
        z.sort_by(f32::total_cmp);
        let min_gap = z
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f32::INFINITY, f32::min);
        // Slots are 2·spread/count wide with jitter in their middle half: gaps ≥ half a slot.
        let half_slot = 2.0 / 3000.0 * 0.5;
        assert!(
            min_gap >= half_slot * 0.99,
            "min gap {min_gap} < {half_slot}"
        );
    }

    #[test]
    fn particles_bad_params_are_errors() {
        let e = build(
            Params::new()
                .with("alpha_min", ParamValue::Float(0.5))
                .with("alpha_max", ParamValue::Float(0.2)),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("alpha_min") && e.contains("alpha_max"), "{e}");
        let e = build(Params::new().with("count", ParamValue::Int(0)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("count") && e.contains("out of range"), "{e}");
        let e = build(Params::new().with("sise", ParamValue::Float(0.1)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown parameter 'sise'"), "{e}");
    }
}
