//! `--shard I/N --balance-from`: balanced shards of a real suite (its groups come from the
//! binary's study table, so the test lives beside it).

use bench_core::shard::{balanced, key_of, PreviousTimes};

#[test]
fn balanced_shards_of_a_suite_cover_every_group_once() {
    let suite = scenarios::Suite::load("smoke").unwrap();
    let groups = bench_core::runner::expand(mfx::STUDIES, &suite, false).unwrap();
    assert!(groups.len() >= 3);
    // The previous run knew the first group only, and found it slow.
    let mut prev = PreviousTimes {
        row_s: 0.5,
        ..Default::default()
    };
    prev.group_s.insert(key_of(&groups[0]), 1000.0);
    for n in 1..=4 {
        let mut seen: Vec<String> = Vec::new();
        for i in 0..n {
            let (mine, load) = balanced(groups.clone(), (i, n), &prev);
            assert_eq!(load.len(), n);
            seen.extend(
                mine.iter()
                    .map(|g| format!("{}#{}", key_of(g), g.study_index)),
            );
        }
        let mut all: Vec<String> = groups
            .iter()
            .map(|g| format!("{}#{}", key_of(g), g.study_index))
            .collect();
        seen.sort();
        all.sort();
        assert_eq!(seen, all, "{n} shards");
    }
    // With two shards the slow group runs alone.
    let (mine, _) = balanced(groups.clone(), (0, 2), &prev);
    assert_eq!(mine.len(), 1);
    assert_eq!(key_of(&mine[0]), key_of(&groups[0]));
}
