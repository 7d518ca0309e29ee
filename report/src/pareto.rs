//! Pareto fronts: the configurations no other one beats on both counts (lower is better on each).

/// Indices of the non-dominated points of `pts` (x, y; lower is better on both), in order of
/// increasing x. A point is dominated when another is no worse on both and better on one; of
/// identical points the first is kept. Points with a non-finite coordinate are never on it.
pub fn front(pts: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..pts.len())
        .filter(|&i| pts[i].0.is_finite() && pts[i].1.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        pts[a]
            .0
            .total_cmp(&pts[b].0)
            .then(pts[a].1.total_cmp(&pts[b].1))
            .then(a.cmp(&b))
    });
    let mut out = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if pts[i].1 < best {
            best = pts[i].1;
            out.push(i);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_front_keeps_only_undominated_points() {
        let pts = [
            (1.0, 0.1),  // fastest
            (2.0, 0.01), // slower, better
            (2.0, 0.05), // same time as the last, worse: dominated
            (3.0, 0.02), // slower and worse than (2, 0.01): dominated
            (4.0, 0.0),  // exact
            (5.0, 0.0),  // exact but slower: dominated
            (f64::NAN, 0.0),
            (1.0, 0.1), // a duplicate of the first
        ];
        assert_eq!(front(&pts), vec![0, 1, 4]);
        assert!(front(&[]).is_empty());
    }
}
