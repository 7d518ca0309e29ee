//! `--shard I/N`: which scene × resolution groups a shard runs. Without more, group index mod N
//! (`runner::shard_groups`). With a previous run's times (`--balance-from RUN`), each group's
//! cost is what it took in that run, and the groups are dealt greedily, longest first, each to
//! the shard with the least so far (Graham's LPT rule: at most 4/3 of the best possible longest
//! shard), ties to the lower index: every shard computes the same partition from the same
//! inputs, and every group lands in exactly one shard.

use std::collections::HashMap;
use std::path::Path;

use schema::{cols, PointKey};

use crate::study::Group;
use crate::{CoreError, Result};

/// The shard (0..n) of each cost, by the LPT rule (see the module notes).
pub fn lpt(costs: &[f64], n: usize) -> Vec<usize> {
    let n = n.max(1);
    let mut order: Vec<usize> = (0..costs.len()).collect();
    // Longest first; equal costs in index order (a stable sort on a total order).
    order.sort_by(|&a, &b| costs[b].total_cmp(&costs[a]));
    let mut load = vec![0.0f64; n];
    let mut shard = vec![0; costs.len()];
    for i in order {
        let s = (0..n)
            .min_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b)))
            .expect("n >= 1");
        load[s] += costs[i].max(0.0);
        shard[i] = s;
    }
    shard
}

/// The key of the group a point belongs to: `study|scene|WxH`.
fn group_key(study: &str, scene: &str, w: u32, h: u32) -> String {
    format!("{study}|{scene}|{w}x{h}")
}

/// The key of a group, as [`PreviousTimes::group_s`] holds it.
pub fn key_of(g: &Group) -> String {
    group_key(g.kind.name(), &g.scene.label(), g.width, g.height)
}

/// Seconds each group took in a previous run, and per row on average (for groups it did not
/// run).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PreviousTimes {
    /// `study|scene|WxH` → seconds.
    pub group_s: HashMap<String, f64>,
    /// The median seconds per row of the previous run (what a group it lacks is charged per row).
    pub row_s: f64,
}

impl PreviousTimes {
    /// From a run folder, a folder of shard folders, a runs table (CSV or Parquet) or a bundle.
    pub fn read(path: &Path) -> Result<PreviousTimes> {
        if mfx_table::bundle::is_bundle(path) {
            let opened = mfx_table::bundle::open(path).map_err(|e| CoreError::Io(e.to_string()))?;
            return PreviousTimes::read(opened.dir());
        }
        let mut tables = Vec::new();
        for f in crate::merge::input_files(path)? {
            tables.push(mfx_table::read(&f).map_err(|e| CoreError::Io(e.to_string()))?);
        }
        let t = PreviousTimes::of(&tables);
        if t.group_s.is_empty() {
            return Err(CoreError::Param(format!(
                "--balance-from {}: no row with a point key and a time",
                path.display()
            )));
        }
        Ok(t)
    }

    /// Each group's seconds: the wall time from the previous group's last row to its own last
    /// row (`timestamp_utc`, whole seconds; scene building, floors and references included),
    /// and never less than its rows' own timed work (`measure_ms` + `prepare_ms` + `judge_ms` +
    /// `fragment_reference_ms`), which is all a file's first group is charged.
    pub fn of(tables: &[mfx_table::Table]) -> PreviousTimes {
        let mut group_s: HashMap<String, f64> = HashMap::new();
        let mut rows_s = Vec::new();
        for t in tables {
            let c = |col: schema::Col| t.col(col.name);
            let (Some(kp), ts) = (c(cols::POINT_KEY), c(cols::TIMESTAMP_UTC)) else {
                continue;
            };
            let work: Vec<Option<usize>> = [
                cols::MEASURE_MS,
                cols::PREPARE_MS,
                cols::JUDGE_MS,
                cols::FRAGMENT_REFERENCE_MS,
            ]
            .into_iter()
            .map(c)
            .collect();
            let secs = |r: &[String]| -> f64 {
                work.iter()
                    .flatten()
                    .filter_map(|&i| r.get(i)?.parse::<f64>().ok())
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .sum::<f64>()
                    / 1e3
            };
            let when = |r: &[String]| {
                ts.and_then(|i| r.get(i))
                    .and_then(|s| chrono::DateTime::parse_from_rfc3339(s).ok())
                    .map(|d| d.timestamp() as f64)
            };
            // (group key, its rows' work, its last row's time), in file order.
            let mut runs: Vec<(String, f64, Option<f64>)> = Vec::new();
            for r in &t.rows {
                let Ok(k) = r[kp].parse::<PointKey>() else {
                    continue;
                };
                let key = group_key(&k.study, &k.scene, k.width, k.height);
                let s = secs(r);
                rows_s.push(s);
                match runs.last_mut() {
                    Some(last) if last.0 == key => {
                        last.1 += s;
                        last.2 = when(r).or(last.2);
                    }
                    _ => runs.push((key, s, when(r))),
                }
            }
            for (i, (key, work, end)) in runs.iter().enumerate() {
                let span = match (i.checked_sub(1).and_then(|p| runs[p].2), end) {
                    (Some(a), Some(b)) if *b >= a => b - a,
                    _ => 0.0,
                };
                *group_s.entry(key.clone()).or_default() += work.max(span);
            }
        }
        rows_s.retain(|s| *s > 0.0);
        rows_s.sort_by(f64::total_cmp);
        let row_s = rows_s.get(rows_s.len() / 2).copied().unwrap_or(1.0);
        PreviousTimes { group_s, row_s }
    }

    /// A group's estimated seconds: its time in the previous run, else its rows × the median row.
    pub fn cost(&self, g: &Group) -> f64 {
        self.group_s
            .get(&key_of(g))
            .copied()
            .unwrap_or_else(|| crate::runner::rows_in(std::slice::from_ref(g)) as f64 * self.row_s)
    }
}

/// The groups of shard `shard.0` of `shard.1` balanced by `prev` (in suite order), and every
/// shard's estimated seconds.
pub fn balanced(
    groups: Vec<Group>,
    shard: (usize, usize),
    prev: &PreviousTimes,
) -> (Vec<Group>, Vec<f64>) {
    let costs: Vec<f64> = groups.iter().map(|g| prev.cost(g)).collect();
    let of = lpt(&costs, shard.1);
    let mut load = vec![0.0; shard.1.max(1)];
    for (s, c) in of.iter().zip(&costs) {
        load[*s] += c;
    }
    let mine = groups
        .into_iter()
        .zip(of)
        .filter(|(_, s)| *s == shard.0)
        .map(|(g, _)| g)
        .collect();
    (mine, load)
}

/// The rule in words, for run.json.
pub const RULE: &str = "greedy longest-processing-time over the previous run's seconds per scene × resolution group (wall time between its last row and the previous group's, at least its rows' measure, prepare, judge and reference ms; a group it lacks: its rows × the median row), ties to the lower shard";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lpt_puts_the_big_group_alone_and_every_group_in_exactly_one_shard() {
        // One 4K group and eight 512² ones: mod 2 gives shard 0 the 4K group and four more.
        let costs = [100.0, 10.0, 10.0, 10.0, 10.0, 10.0, 10.0, 10.0, 10.0];
        let s = lpt(&costs, 2);
        assert_eq!(s[0], 0);
        assert!(s[1..].iter().all(|&x| x == 1), "{s:?}");
        let load = |n: usize, s: &[usize]| -> Vec<f64> {
            let mut l = vec![0.0; n];
            for (i, &k) in s.iter().enumerate() {
                l[k] += costs[i];
            }
            l
        };
        assert_eq!(load(2, &s), [100.0, 80.0]);
        let modn: Vec<usize> = (0..costs.len()).map(|i| i % 2).collect();
        assert_eq!(load(2, &modn), [140.0, 40.0], "what mod N gives");
        // Every group in exactly one of N shards, for any N; the same inputs, the same answer.
        for n in 1..=12 {
            let a = lpt(&costs, n);
            assert_eq!(a.len(), costs.len());
            assert!(a.iter().all(|&k| k < n));
            assert_eq!(a, lpt(&costs, n), "deterministic");
        }
        // Ties go to the lower index.
        assert_eq!(lpt(&[1.0, 1.0, 1.0], 3), [0, 1, 2]);
    }

    fn table(rows: &[(&str, &str, &str)]) -> mfx_table::Table {
        mfx_table::Table {
            header: vec![
                cols::POINT_KEY.name.into(),
                cols::TIMESTAMP_UTC.name.into(),
                cols::MEASURE_MS.name.into(),
            ],
            rows: rows
                .iter()
                .map(|(k, t, m)| vec![k.to_string(), t.to_string(), m.to_string()])
                .collect(),
            metadata: Vec::new(),
        }
    }

    #[test]
    fn a_group_costs_the_wall_time_since_the_previous_group_and_at_least_its_work() {
        let t = table(&[
            (
                "methods|quads|64x64|floor_depth|",
                "2026-12-01T00:00:00Z",
                "500",
            ),
            ("methods|quads|64x64|wboit|", "2026-12-01T00:00:01Z", "700"),
            // The 4K group: 40 s after the first group's last row, 30 s of its rows' work.
            (
                "methods|quads|4096x4096|floor_depth|",
                "2026-12-01T00:00:21Z",
                "10000",
            ),
            (
                "methods|quads|4096x4096|wboit|",
                "2026-12-01T00:00:41Z",
                "20000",
            ),
            (
                "methods|quads|128x128|wboit|",
                "2026-12-01T00:00:41Z",
                "300",
            ),
        ]);
        let p = PreviousTimes::of(&[t]);
        assert!(
            (p.group_s["methods|quads|64x64"] - 1.2).abs() < 1e-9,
            "first: its work"
        );
        assert!((p.group_s["methods|quads|4096x4096"] - 40.0).abs() < 1e-9);
        assert!(
            (p.group_s["methods|quads|128x128"] - 0.3).abs() < 1e-9,
            "0 s span: its work"
        );
        assert!((p.row_s - 0.7).abs() < 1e-9, "median row");
    }
}
