//! Seeded random pixels for the twins' tests.

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

use crate::{composite, RefFragment};

/// A reference fragment at view distance `z` (window depth z/(z + 1), monotone in z).
pub fn frag(z: f64, color: [f64; 4], prim: u32) -> RefFragment {
    RefFragment {
        depth: z / (z + 1.0),
        view_z: z,
        color,
        normal: [0.0, 0.0, 1.0],
        object_id: prim,
        front_facing: true,
        prim,
        depth_slope: 0.0,
    }
}

/// `n` fragments with distinct depths in (near, far), colours in [0.1, 0.9], opacity in
/// [a_lo, a_hi], nearest first (as [`crate::FragmentLists`] stores them), with a
/// random arrival order (prim ids a random permutation).
pub fn pixel(
    rng: &mut Pcg32,
    n: usize,
    a_lo: f64,
    a_hi: f64,
    near: f64,
    far: f64,
) -> Vec<RefFragment> {
    let mut prims: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        prims.swap(i, rng.random_range(0..=i));
    }
    // Stratified depths: distinct and sorted.
    (0..n)
        .map(|i| {
            let t = (i as f64 + 0.1 + 0.8 * rng.random::<f64>()) / n as f64;
            let c = [
                rng.random_range(0.1..0.9),
                rng.random_range(0.1..0.9),
                rng.random_range(0.1..0.9),
                rng.random_range(a_lo..=a_hi),
            ];
            frag(near + (far - near) * t, c, prims[i])
        })
        .collect()
}

pub fn rng(seed: u64) -> Pcg32 {
    Pcg32::seed_from_u64(seed)
}

/// The exact answer: every fragment composited nearest first.
pub fn exact(list: &[RefFragment]) -> [f64; 4] {
    let mut v = list.to_vec();
    v.sort_by(|a, b| a.view_z.total_cmp(&b.view_z));
    composite(v.iter())
}

/// The same fragments in arrival (prim) order.
pub fn arrival(list: &[RefFragment]) -> Vec<RefFragment> {
    let mut v = list.to_vec();
    v.sort_by_key(|f| f.prim);
    v
}

pub fn max_abs(a: [f64; 4], b: [f64; 4]) -> f64 {
    a.iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Checks the invariants every twin's output has: finite, A in [0, 1], 0 ≤ C ≤ A per channel
/// (colours are in [0, 1], so premultiplied colour cannot exceed coverage).
pub fn assert_valid(v: [f64; 4], what: &str) {
    assert!(v.iter().all(|x| x.is_finite()), "{what}: non-finite {v:?}");
    let eps = 1e-12;
    assert!(
        (-eps..=1.0 + eps).contains(&v[3]),
        "{what}: A outside [0,1]: {v:?}"
    );
    for c in &v[..3] {
        assert!(
            *c >= -eps && *c <= v[3] + 1e-9,
            "{what}: colour outside [0, A]: {v:?}"
        );
    }
}
