//! The f64 truths of Bavoil 2007 §6.3's sorting-and-blending applications (Fig. 6.4), computed
//! from a pixel's exact depth-sorted fragment list: the faces of a tetrahedral mesh, each
//! fragment carrying the mesh's piecewise-linear scalar field (the colour's red channel, as the
//! `tets` scene stores it). Consecutive fragments f1, f2 bound one ray segment inside one
//! tetrahedron, along which the scalar is linear in the linear view depth (§6.3: "the first and
//! second nearest fragments to the eye [...] form a ray segment").
//!
//! - [`volume`] (§6.3.2, direct volume rendering): each segment's colour and opacity from the
//!   transfer function, composited front to back. The thesis looks the segment up "in a
//!   precomputed table of volume rendering integrals" indexed by (s_f, s_b, distance); here the
//!   table's entry is computed in closed form: extinction τ(s) = σ·s is linear in s, so the
//!   segment's optical depth is exactly σ·(s_f + s_b)/2·Δz, and the emitted colour is the
//!   transfer function at the segment's mean scalar (constant over the segment).
//! - [`isosurface`] (§6.3.1): in the first segment whose scalars bracket the iso-value, the
//!   depths are interpolated linearly to the crossing; the image is (view depth of the nearest
//!   crossing, 0, 0, 1), or 0 where the ray never crosses it. The thesis shades the result by
//!   central differences of these depths in a post pass; the depth is what that pass reads.
//!
//! Depths are linear view depths (world units along the view axis), as translucency's
//! thickness: the scalar is affine in them along a ray, window depth is not.

use crate::RefFragment;

/// The scalar a fragment carries (the `tets` scene's field, in the colour's red channel).
pub fn scalar(f: &RefFragment) -> f64 {
    f.color[0]
}

/// The transfer function's colour at scalar `s` ∈ [0, 1]: a ramp from blue through green to
/// red (the WGSL `fold_transfer`).
pub fn transfer(s: f64) -> [f64; 3] {
    [s, 4.0 * s * (1.0 - s), 1.0 - s]
}

/// Front-to-back composite of the ray segments between consecutive fragments (given nearest
/// first) with extinction σ·s per unit view depth: premultiplied (C, A), A = 1 − transmittance.
pub fn volume<'a>(frags: impl IntoIterator<Item = &'a RefFragment>, sigma: f64) -> [f64; 4] {
    let mut acc = [0.0f64; 4];
    let mut prev: Option<(f64, f64)> = None;
    for f in frags {
        let (s, z) = (scalar(f), f.view_z);
        if let Some((ps, pz)) = prev {
            let mean = 0.5 * (ps + s);
            let alpha = -(-(sigma * mean * (z - pz)).max(0.0)).exp_m1();
            let t = 1.0 - acc[3];
            for (a, c) in acc.iter_mut().zip(transfer(mean)) {
                *a += t * alpha * c;
            }
            acc[3] += t * alpha;
        }
        prev = Some((s, z));
    }
    acc
}

/// The nearest crossing of `iso` between consecutive fragments (given nearest first), as
/// (view depth, 0, 0, 1); zero where no segment brackets it. A segment brackets `iso` where
/// (s1 − iso)·(s2 − iso) ≤ 0 and s1 ≠ s2 (the WGSL fold's rule, so a crossing at a fragment is
/// found once, in the segment in front of it).
pub fn isosurface<'a>(frags: impl IntoIterator<Item = &'a RefFragment>, iso: f64) -> [f64; 4] {
    let mut prev: Option<(f64, f64)> = None;
    for f in frags {
        let (s, z) = (scalar(f), f.view_z);
        if let Some((ps, pz)) = prev {
            if (ps - iso) * (s - iso) <= 0.0 && ps != s {
                let t = (iso - ps) / (s - ps);
                return [pz + t * (z - pz), 0.0, 0.0, 1.0];
            }
        }
        prev = Some((s, z));
    }
    [0.0; 4]
}

/// Unit roundoff of f32.
const U: f64 = 1.0 / 16_777_216.0;

/// A max-abs bound per pixel within which an f32 GPU evaluation of [`volume`] over the same
/// fragments equals the f64 one, to first order. The GPU interpolates s and z in f32 (≤ 8u
/// relative each, as the transparency bound assumes for colour and alpha), so a segment's
/// Δz is off by ≤ 16u·z_max and its mean scalar by ≤ 8u: its optical depth x = σ·s̄·Δz by
/// ≤ σ·(16u·z_max + 8u·Δz) + 4u·x, its opacity 1 − e^(−x) by that + 4u (slope ≤ 1), and its
/// colour by ≤ 4·8u (the ramp's slope ≤ 4). Each segment then moves the composite by at most
/// its opacity error plus its colour error, and the compositing itself is transparency's
/// (32n + 4)u. Doubled for the second-order terms.
pub fn volume_bound(frags: &[RefFragment], sigma: f64) -> f64 {
    let n = frags.len() as f64;
    let z_max = frags.last().map_or(0.0, |f| f.view_z);
    let span = z_max - frags.first().map_or(0.0, |f| f.view_z);
    let segments = (n - 1.0).max(0.0);
    let opacity = sigma * (16.0 * U * z_max * segments + 12.0 * U * span) + 4.0 * U * segments;
    let colour = 32.0 * U * segments;
    2.0 * (opacity + colour + (32.0 * n + 4.0) * U)
}

/// A max-abs bound within which an f32 evaluation of [`isosurface`] over the same fragments
/// equals the f64 one, to first order, where the crossing segment is the same: z = z1 +
/// t·(z2 − z1) with z1, z2 off by ≤ 8u·z2 each and t = (iso − s1)/(s2 − s1) off by ≤
/// 16u/|s2 − s1| + 4u (s ≤ 1), so z by ≤ 16u·z2 + |z2 − z1|·(16u/|s2 − s1| + 4u) + 4u·z2.
/// Doubled for the second-order terms. `None` where the truth has no crossing.
pub fn isosurface_bound(frags: &[RefFragment], iso: f64) -> Option<f64> {
    frags.windows(2).find_map(|w| {
        let (s1, s2) = (scalar(&w[0]), scalar(&w[1]));
        ((s1 - iso) * (s2 - iso) <= 0.0 && s1 != s2).then(|| {
            let (z1, z2) = (w[0].view_z, w[1].view_z);
            2.0 * (20.0 * U * z2 + (z2 - z1) * (16.0 * U / (s2 - s1).abs() + 4.0 * U))
        })
    })
}

/// How close the ray comes to touching `iso` without a crossing the f32 evaluation is sure to
/// share: the smallest |s − iso| over the fragments up to and including the first crossing
/// segment's far end (all of them without a crossing). Where it is within the GPU's scalar error
/// (8u), f32 may find a crossing the f64 truth does not, or miss one, at a fragment that merely
/// touches the iso-value: a discrete difference no arithmetic bound covers.
pub fn isosurface_margin(frags: &[RefFragment], iso: f64) -> f64 {
    let mut m = f64::INFINITY;
    for (i, f) in frags.iter().enumerate() {
        m = m.min((scalar(f) - iso).abs());
        if i > 0 {
            let ps = scalar(&frags[i - 1]);
            if (ps - iso) * (scalar(f) - iso) <= 0.0 && ps != scalar(f) {
                break;
            }
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frag(z: f64, s: f64) -> RefFragment {
        RefFragment {
            depth: z / 100.0,
            view_z: z,
            color: [s, s, s, 0.2],
            normal: [0.0, 0.0, 1.0],
            object_id: 0,
            front_facing: true,
            prim: 0,
            depth_slope: 0.0,
        }
    }

    #[test]
    fn a_constant_field_is_beer_lambert_over_the_whole_span() {
        // s = 0.5 everywhere, σ = 2: opacity 1 − exp(−2·0.5·(4 − 1)), however the span is cut.
        let one = volume(&[frag(1.0, 0.5), frag(4.0, 0.5)], 2.0);
        let cut = volume(
            &[
                frag(1.0, 0.5),
                frag(1.7, 0.5),
                frag(2.5, 0.5),
                frag(4.0, 0.5),
            ],
            2.0,
        );
        let a = 1.0 - (-3.0f64).exp();
        assert!((one[3] - a).abs() < 1e-15 && (cut[3] - a).abs() < 1e-15);
        let c = transfer(0.5);
        for i in 0..3 {
            assert!((one[i] - a * c[i]).abs() < 1e-15 && (cut[i] - one[i]).abs() < 1e-15);
        }
        // One fragment bounds no segment: nothing is composited.
        assert_eq!(volume(&[frag(1.0, 0.9)], 2.0), [0.0; 4]);
    }

    #[test]
    fn a_linear_field_integrates_its_optical_depth_exactly() {
        // s from 0 to 1 over Δz = 2 with σ = 1.5: ∫σ·s dz = 1.5·2·0.5 = 1.5, however split.
        let frags: Vec<_> = (0..=4)
            .map(|i| frag(1.0 + 0.5 * i as f64, 0.25 * i as f64))
            .collect();
        let a = volume(&frags, 1.5)[3];
        assert!((a - (1.0 - (-1.5f64).exp())).abs() < 1e-15, "{a}");
    }

    #[test]
    fn the_isosurface_is_the_nearest_crossing_interpolated_in_view_depth() {
        let frags = [
            frag(1.0, 0.1),
            frag(2.0, 0.3),
            frag(4.0, 0.7),
            frag(5.0, 0.2),
        ];
        // 0.5 is crossed first between z = 2 and 4, halfway in s: z = 3 (then again behind).
        assert_eq!(isosurface(&frags, 0.5), [3.0, 0.0, 0.0, 1.0]);
        assert_eq!(isosurface(&frags, 0.9), [0.0; 4], "never reached");
        // A crossing exactly at a fragment is found in the segment in front of it.
        assert_eq!(isosurface(&frags, 0.3)[0], 2.0);
        assert!((isosurface_margin(&frags, 0.9) - 0.2).abs() < 1e-15);
        let b = isosurface_bound(&frags, 0.5).unwrap();
        assert!(b > 0.0 && b < 1e-4, "a few hundred f32 roundoffs: {b}");
    }
}
