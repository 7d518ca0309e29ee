//! The soft-shadow reference: visibility of a square area light by ray tracing, in f64.
//!
//! A median-split BVH over the scene's triangles (leaves of at most 4) answers any-hit queries;
//! each evaluated point shoots m×m shadow rays at jittered stratified points of the light square
//! (one ray per stratum), so an edge crossing the light costs at most one row of strata: the
//! stratification error of a straight edge is ≤ 1/m. Slow and obviously right, parallel over
//! pixel rows with rayon; the layered shadow map is judged against this, never against the GPU.

use glam::{DMat4, DVec3};
use rayon::prelude::*;
use scenarios::{AreaLight, Scene};

/// Shadow rays start this fraction of the way to the light: skips the receiver's own triangle
/// (the G-buffer point lies within f32 rounding, ~1e-7 relative, of it) while any occluder
/// further than 1e-5 of the distance (4e-5 world units in the shipped scenes, far below their
/// thinnest gap) still counts.
pub const T_MIN: f64 = 1e-5;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first triangle; inner: index of the left child (the right one follows it).
    first_or_left: u32,
    /// Triangles in a leaf; 0 for an inner node.
    count: u32,
}

/// Bounding volume hierarchy over triangles (world space, f64).
pub struct Bvh {
    nodes: Vec<Node>,
    tris: Vec<[DVec3; 3]>,
}

const LEAF: usize = 4;

impl Bvh {
    pub fn from_scene(scene: &Scene) -> Bvh {
        let m = &scene.mesh;
        let p = |i: u32| glam::Vec3::from(m.positions[i as usize]).as_dvec3();
        Bvh::build(
            m.indices
                .chunks_exact(3)
                .map(|t| [p(t[0]), p(t[1]), p(t[2])])
                .collect(),
        )
    }

    pub fn build(tris: Vec<[DVec3; 3]>) -> Bvh {
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let cent: Vec<DVec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF + 1);
        nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            first_or_left: 0,
            count: 0,
        });
        // Explicit stack of (node, range) so deep meshes cannot overflow the thread stack.
        let mut stack = vec![(0usize, 0usize, order.len())];
        while let Some((ni, a, b)) = stack.pop() {
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let (mut clo, mut chi) = (lo, hi);
            for &t in &order[a..b] {
                for v in tris[t as usize] {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                clo = clo.min(cent[t as usize]);
                chi = chi.max(cent[t as usize]);
            }
            nodes[ni].lo = lo;
            nodes[ni].hi = hi;
            if b - a <= LEAF {
                nodes[ni].first_or_left = a as u32;
                nodes[ni].count = (b - a) as u32;
                continue;
            }
            let ext = chi - clo;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = (a + b) / 2;
            order[a..b].select_nth_unstable_by(mid - a, |&i, &j| {
                cent[i as usize][axis].total_cmp(&cent[j as usize][axis])
            });
            let left = nodes.len();
            let blank = nodes[0];
            nodes.push(blank);
            nodes.push(blank);
            nodes[ni].first_or_left = left as u32;
            nodes[ni].count = 0;
            stack.push((left, a, mid));
            stack.push((left + 1, mid, b));
        }
        let tris = order.iter().map(|&i| tris[i as usize]).collect();
        Bvh { nodes, tris }
    }

    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// True if any triangle crosses the segment o + t·d, t in (tmin, tmax).
    pub fn occluded(&self, o: DVec3, d: DVec3, tmin: f64, tmax: f64) -> bool {
        if self.tris.is_empty() {
            return false;
        }
        let inv = DVec3::ONE / d;
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = &self.nodes[stack[sp] as usize];
            if !slab_hit(n.lo, n.hi, o, inv, tmin, tmax) {
                continue;
            }
            if n.count > 0 {
                let f = n.first_or_left as usize;
                for t in &self.tris[f..f + n.count as usize] {
                    if let Some(h) = intersect(o, d, t) {
                        if h > tmin && h < tmax {
                            return true;
                        }
                    }
                }
            } else {
                stack[sp] = n.first_or_left;
                stack[sp + 1] = n.first_or_left + 1;
                sp += 2;
            }
        }
        false
    }
}

/// Ray–box slab test (IEEE infinities handle axis-parallel rays).
fn slab_hit(lo: DVec3, hi: DVec3, o: DVec3, inv: DVec3, tmin: f64, tmax: f64) -> bool {
    let t0 = (lo - o) * inv;
    let t1 = (hi - o) * inv;
    let near = t0.min(t1).max_element().max(tmin);
    let far = t0.max(t1).min_element().min(tmax);
    // NaN (0·inf on a face) compares false: treat as a hit so no triangle is ever skipped.
    near.partial_cmp(&far) != Some(std::cmp::Ordering::Greater)
}

/// Möller–Trumbore: ray parameter of the hit, or None (both faces count: shadows have no culling).
fn intersect(o: DVec3, d: DVec3, t: &[DVec3; 3]) -> Option<f64> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

/// The light's frame in f64: centre, unit axes of the square, its facing direction, side.
#[derive(Clone, Copy, Debug)]
pub struct LightFrame {
    pub center: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    pub forward: DVec3,
    pub size: f64,
}

impl LightFrame {
    pub fn of(light: &AreaLight) -> LightFrame {
        let view: DMat4 = light.camera.view();
        // Rows of the view rotation are the light's axes in world space; view looks down −z.
        let r = view.transpose();
        LightFrame {
            center: light.camera.eye.into(),
            right: r.x_axis.truncate(),
            up: r.y_axis.truncate(),
            forward: -r.z_axis.truncate(),
            size: light.size,
        }
    }

    /// World point of the light square at (u, v) in [−0.5, 0.5]².
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        self.center + self.right * (u * self.size) + self.up * (v * self.size)
    }
}

/// Deterministic hash → [0, 1) (PCG output function), so every run jitters identically.
fn jitter(mut x: u64) -> f64 {
    x = x
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let xs = (((x >> 18) ^ x) >> 27) as u32;
    let rot = (x >> 59) as u32;
    xs.rotate_right(rot) as f64 / 4294967296.0
}

/// Fraction of the light square visible from `p`: m×m jittered strata, one ray each.
pub fn visibility(bvh: &Bvh, light: &LightFrame, p: DVec3, m: u32, seed: u64) -> f64 {
    let mut seen = 0u32;
    for a in 0..m {
        for b in 0..m {
            let k = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ ((a as u64) << 32 | b as u64);
            let u = (a as f64 + jitter(k)) / m as f64 - 0.5;
            let v = (b as f64 + jitter(k ^ 0xA5A5_A5A5)) / m as f64 - 0.5;
            let q = light.point(u, v);
            if !bvh.occluded(p, q - p, T_MIN, 1.0) {
                seen += 1;
            }
        }
    }
    seen as f64 / (m * m) as f64
}

/// Reference visibility of every pixel that has a point (None elsewhere), rows in parallel.
pub fn visibility_image(
    bvh: &Bvh,
    light: &LightFrame,
    points: &[Option<DVec3>],
    width: usize,
    m: u32,
) -> Vec<Option<f64>> {
    points
        .par_chunks(width.max(1))
        .enumerate()
        .flat_map_iter(|(y, row)| {
            row.iter()
                .enumerate()
                .map(move |(x, p)| p.map(|p| visibility(bvh, light, p, m, (y * width + x) as u64)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use scenarios::Camera;

    /// A unit light 4 above the origin looking down, like the shipped scenes'.
    fn light() -> LightFrame {
        let mut cam = Camera::look_at(DVec3::new(0.0, 4.0, 0.0), DVec3::ZERO, 60.0, 0.4, 8.0);
        cam.up = [0.0, 0.0, -1.0];
        LightFrame::of(&AreaLight {
            camera: cam,
            size: 1.0,
        })
    }

    /// Horizontal square [x0, x1]×[z0, z1] at height y as two triangles.
    fn square(x0: f64, x1: f64, z0: f64, z1: f64, y: f64) -> Vec<[DVec3; 3]> {
        let a = DVec3::new(x0, y, z0);
        let b = DVec3::new(x1, y, z0);
        let c = DVec3::new(x1, y, z1);
        let d = DVec3::new(x0, y, z1);
        vec![[a, b, c], [a, c, d]]
    }

    #[test]
    fn light_frame_is_orthonormal_and_faces_down() {
        let l = light();
        assert!((l.forward - DVec3::NEG_Y).length() < 1e-12);
        assert!((l.right - DVec3::X).length() < 1e-12);
        assert!((l.up - DVec3::NEG_Z).length() < 1e-12);
    }

    #[test]
    fn open_sky_is_fully_lit_and_a_big_roof_fully_occludes() {
        let l = light();
        let p = DVec3::new(0.3, 0.0, -0.2);
        let empty = Bvh::build(square(5.0, 6.0, 5.0, 6.0, 2.0));
        assert_eq!(visibility(&empty, &l, p, 8, 1), 1.0);
        let roof = Bvh::build(square(-3.0, 3.0, -3.0, 3.0, 2.0));
        assert_eq!(visibility(&roof, &l, p, 8, 1), 0.0);
        // A roof below the receiver does not shadow it (the segment ends at the light).
        let floor = Bvh::build(square(-3.0, 3.0, -3.0, 3.0, -1.0));
        assert_eq!(visibility(&floor, &l, p, 8, 1), 1.0);
    }

    #[test]
    fn half_covered_light_is_half_visible_within_stratification_error() {
        let l = light();
        // Receiver at the origin, an occluder edge at x = 0 halfway up: it hides the light's
        // x < 0 half exactly (similar triangles), and x < 0.25 for an edge at x = 0.125.
        let p = DVec3::ZERO;
        for (edge, expect) in [(0.0, 0.5), (0.125, 0.25)] {
            let bvh = Bvh::build(square(-3.0, edge, -3.0, 3.0, 2.0));
            for m in [4u32, 8, 16] {
                let v = visibility(&bvh, &l, p, m, 7);
                // One column of strata straddles the edge: error ≤ 1/m.
                assert!(
                    (v - expect).abs() <= 1.0 / m as f64 + 1e-12,
                    "edge {edge}, m {m}: {v} vs {expect}"
                );
            }
        }
        // Edge on a stratum boundary (m even, edge at the centre): exact.
        let bvh = Bvh::build(square(-3.0, 0.0, -3.0, 3.0, 2.0));
        assert_eq!(visibility(&bvh, &l, p, 8, 3), 0.5);
    }

    #[test]
    fn bvh_agrees_with_brute_force_on_random_triangles() {
        let mut k = 0u64;
        let mut r = || {
            k += 1;
            jitter(k * 7919) * 4.0 - 2.0
        };
        let tris: Vec<[DVec3; 3]> = (0..300)
            .map(|_| {
                let c = DVec3::new(r(), r().abs() * 0.8 + 0.2, r());
                let mut e = || DVec3::new(r(), r(), r()) * 0.15;
                let (a, b) = (e(), e());
                [c, c + a, c + b]
            })
            .collect();
        let bvh = Bvh::build(tris.clone());
        let l = light();
        for i in 0..400 {
            let p = DVec3::new(r(), 0.0, r());
            let q = l.point(jitter(i) - 0.5, jitter(i + 999) - 0.5);
            let brute = tris
                .iter()
                .any(|t| intersect(p, q - p, t).is_some_and(|h| h > T_MIN && h < 1.0));
            assert_eq!(bvh.occluded(p, q - p, T_MIN, 1.0), brute, "ray {i}");
        }
    }
}
