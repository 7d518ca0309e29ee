//! Seeded interleaving of repetitions (Google benchmark's `--benchmark_enable_random_interleaving`):
//! instead of all samples of point A, then all of B, the samples of a group's points are taken
//! in a shuffled order, so a slow drift (clock, temperature, a background process) spreads over
//! every point as noise instead of becoming a bias between them. The seed is recorded
//! (`order_seed`) so the order can be reproduced. Shuffles are Fisher–Yates from a PCG64 stream
//! (`rand`'s `SliceRandom::shuffle`): deterministic for a seed and a `rand` major version.

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_pcg::Pcg64;

/// A fixed number of repetitions per point: every index in `0..points` appears
/// `reps_per_point` times, in a seeded random order.
pub fn interleave_order(points: usize, reps_per_point: usize, seed: u64) -> Vec<usize> {
    let mut v: Vec<usize> = (0..points)
        .flat_map(|p| std::iter::repeat_n(p, reps_per_point))
        .collect();
    v.shuffle(&mut Pcg64::seed_from_u64(seed));
    v
}

/// With a stopping rule the number of samples per point is not known in advance: sample in
/// rounds, one sample of every still-active point per round, in an order shuffled afresh for
/// each round (`round` mixed into the seed). Drop a point from `active` once its sampler stops.
pub fn round_order(active: &[usize], round: u64, seed: u64) -> Vec<usize> {
    let mut v = active.to_vec();
    // Distinct, well-mixed stream per round (the golden-ratio increment of splitmix64).
    let s = seed ^ round.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    v.shuffle(&mut Pcg64::seed_from_u64(s));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_point_appears_reps_times_in_a_seeded_order() {
        let o = interleave_order(5, 4, 11);
        assert_eq!(o.len(), 20);
        for p in 0..5 {
            assert_eq!(o.iter().filter(|&&x| x == p).count(), 4);
        }
        assert_eq!(o, interleave_order(5, 4, 11), "deterministic");
        assert_ne!(o, interleave_order(5, 4, 12), "seed matters");
        let blocked: Vec<usize> = (0..5).flat_map(|p| [p; 4]).collect();
        assert_ne!(o, blocked, "actually interleaved");
        assert!(interleave_order(0, 3, 1).is_empty());
        assert!(interleave_order(3, 0, 1).is_empty());
    }

    #[test]
    fn rounds_are_permutations_that_change_between_rounds() {
        let active = [0, 2, 3, 7, 9, 10, 12];
        let r0 = round_order(&active, 0, 5);
        let mut sorted = r0.clone();
        sorted.sort();
        assert_eq!(sorted, active);
        assert_eq!(r0, round_order(&active, 0, 5));
        let distinct = (0..10)
            .map(|r| round_order(&active, r, 5))
            .collect::<std::collections::HashSet<_>>()
            .len();
        assert!(distinct >= 8, "{distinct} distinct orders in 10 rounds");
    }
}
