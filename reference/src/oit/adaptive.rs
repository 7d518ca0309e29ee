//! Adaptive transparency (Salvi, Montgomery & Lefohn, "Adaptive Transparency", HPG 2011, §4):
//! each pixel's visibility function vis(z) (transmittance between the eye and depth z) is kept
//! as at most k nodes (dᵢ, tᵢ) sorted by depth, a step function: vis(z) = t of the last node with
//! dᵢ < z, 1 before the first.
//!
//! Insertion of a fragment (z, α), in the given (arrival) order: a node (z, vis(z)·(1 − α)) goes
//! in front of any node of equal depth, and every node behind it is multiplied by 1 − α (§4.1).
//! If that makes k + 1 nodes, the node whose removal changes the area under vis(z) least is
//! removed (§4.2): removing node i ≥ 1 gives node i − 1 node i's transmittance, which changes
//! the area by (dᵢ − dᵢ₋₁)·(tᵢ₋₁ − tᵢ); the first node is never removed and the smallest index
//! wins ties. This is the rule of the authors' sample code; absorption moves forward, so the
//! compressed vis(z) is never above the exact one.
//!
//! Colour (the paper's second, resolve pass over the same fragments): C = Σ vis(zᵢ)·αᵢ·cᵢ, a
//! fragment seen through the compressed function just in front of it; A = 1 − t of the last
//! node, which removal never changes (exactly Π(1 − αᵢ)).
//!
//! Depth is the view distance ([`super::Frag::z`]), so areas are in world units along the view
//! axis.

use super::mlab::Layered;
use super::{to_f64, Frag, Order, Real};
use crate::RefFragment;

/// One node of the visibility function: the transmittance just behind depth `z`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node<T> {
    pub z: T,
    pub trans: T,
}

/// vis(z): transmittance of `nodes` strictly in front of `z`.
pub fn visibility<T: Real>(nodes: &[Node<T>], z: T) -> T {
    nodes
        .iter()
        .take_while(|n| n.z < z)
        .last()
        .map_or(T::ONE, |n| n.trans)
}

/// The compressed visibility function of `frags` (in arrival order) with at most k nodes, and
/// the number of node removals. Panics if k = 0.
pub fn visibility_nodes<T: Real>(frags: &[Frag<T>], k: usize) -> (Vec<Node<T>>, u32) {
    assert!(k >= 1, "adaptive transparency needs at least one node");
    let mut nodes: Vec<Node<T>> = Vec::with_capacity(k + 1);
    let mut removals = 0;
    for f in frags {
        let t = T::ONE - f.alpha();
        let at = nodes.iter().take_while(|n| n.z < f.z).count();
        let before = if at == 0 { T::ONE } else { nodes[at - 1].trans };
        for n in &mut nodes[at..] {
            n.trans *= t;
        }
        nodes.insert(
            at,
            Node {
                z: f.z,
                trans: before * t,
            },
        );
        if nodes.len() > k {
            // k = 1 keeps the single node: merge the second into the first.
            let mut best = 1;
            let mut best_err = None;
            for i in 1..nodes.len() {
                let err = (nodes[i].z - nodes[i - 1].z) * (nodes[i - 1].trans - nodes[i].trans);
                if best_err.is_none_or(|b| err < b) {
                    best = i;
                    best_err = Some(err);
                }
            }
            nodes[best - 1].trans = nodes[best].trans;
            nodes.remove(best);
            removals += 1;
        }
    }
    (nodes, removals)
}

/// Adaptive transparency with k nodes at precision `T`: visibility from `frags` in their given
/// order, then every fragment shaded through it. `merges` counts node removals.
pub fn adaptive_t<T: Real>(frags: &[Frag<T>], k: usize) -> Layered<T> {
    let (nodes, removals) = visibility_nodes(frags, k);
    let mut c = [T::ZERO; 3];
    for f in frags {
        let w = visibility(&nodes, f.z) * f.alpha();
        for (ci, fc) in c.iter_mut().zip(&f.color) {
            *ci += w * *fc;
        }
    }
    let t = nodes.last().map_or(T::ONE, |n| n.trans);
    Layered {
        rgba: [c[0], c[1], c[2], T::ONE - t],
        merges: removals,
    }
}

/// Adaptive transparency with k nodes; `frags` in the order they arrive.
pub fn adaptive(frags: &[RefFragment], k: usize) -> [f64; 4] {
    let f: Vec<Frag<f64>> = frags.iter().map(Frag::of).collect();
    to_f64(adaptive_t(&f, k).rgba)
}

/// Adaptive transparency of one reference pixel replayed in `order`, with its removal count.
pub fn adaptive_pixel(list: &[RefFragment], k: usize, order: Order) -> ([f64; 4], u32) {
    let r = adaptive_t(&super::frags::<f64>(list, order), k);
    (to_f64(r.rgba), r.merges)
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;
    use rand::Rng;

    #[test]
    fn adaptive_is_exact_when_depth_complexity_is_at_most_k() {
        let mut rng = rng(21);
        for k in [1usize, 2, 4, 8] {
            for n in 0..=k {
                for _ in 0..20 {
                    let px = pixel(&mut rng, n, 0.05, 0.95, 1.0, 10.0);
                    let (got, removals) = adaptive_pixel(&px, k, Order::Arrival);
                    assert_eq!(removals, 0);
                    // vis(zᵢ) is the exact product of the nearer fragments: rounding only.
                    assert!(max_abs(got, exact(&px)) < 1e-12, "k {k} n {n}");
                }
            }
        }
    }

    #[test]
    fn adaptive_alpha_is_exact_and_colour_never_brighter_than_exact() {
        let mut rng = rng(22);
        for k in [1usize, 2, 4, 8] {
            for _ in 0..100 {
                let n = rng.random_range(0..64);
                let px = pixel(&mut rng, n, 0.02, 0.95, 1.0, 10.0);
                let (got, removals) = adaptive_pixel(&px, k, Order::Arrival);
                assert_eq!(removals as usize, n.saturating_sub(k));
                let want = exact(&px);
                assert_valid(got, "adaptive");
                assert!((got[3] - want[3]).abs() < 1e-12, "A = 1 − Π(1 − α) exactly");
                // Removal moves absorption forward, so every vis(zᵢ) ≤ the exact one and each
                // channel (a sum of vis·α·c ≥ 0 terms) is at most the exact value.
                for ch in 0..3 {
                    assert!(got[ch] <= want[ch] + 1e-12, "ch {ch}: {got:?} > {want:?}");
                }
            }
        }
    }

    #[test]
    fn adaptive_removes_the_least_area_node() {
        // Nodes at 1, 2, 2.1 (α 0.5 each): removing the node at 2.1 costs (2.1 − 2)·0.125, the
        // one at 2 costs 1·0.25: the third goes, node 2 takes its transmittance 0.125.
        let f = |z: f64| Frag {
            z,
            color: [1.0, 1.0, 1.0, 0.5],
        };
        let (nodes, removals) = visibility_nodes(&[f(1.0), f(2.0), f(2.1)], 2);
        assert_eq!(removals, 1);
        assert_eq!(
            nodes,
            vec![
                Node { z: 1.0, trans: 0.5 },
                Node {
                    z: 2.0,
                    trans: 0.125
                }
            ]
        );
        // The fragment at 2.1 is now seen through 0.125 instead of 0.25.
        assert_eq!(visibility(&nodes, 2.1), 0.125);
        assert_eq!(visibility(&nodes, 2.0), 0.5);
    }

    #[test]
    fn adaptive_f32_twin_follows_f64_to_1e5() {
        let mut rng = rng(23);
        for _ in 0..200 {
            let px = arrival(&pixel(&mut rng, 300, 0.02, 0.3, 1.0, 10.0));
            let f32s: Vec<Frag<f32>> = px.iter().map(Frag::of).collect();
            let got = to_f64(adaptive_t(&f32s, 4).rgba);
            assert!(max_abs(got, adaptive(&px, 4)) < 1e-5);
        }
    }
}
