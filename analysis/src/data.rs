//! Reading runs.csv: rows as column → text maps, with typed accessors.

use schema::StudyKind;
use schema::{cols, Col, Flag, FlagSet, Status};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// One CSV row.
#[derive(Clone, Debug, Default)]
pub struct Rec(pub BTreeMap<String, String>);

impl Rec {
    /// The cell, or "" when absent or empty.
    pub fn get(&self, col: Col) -> &str {
        self.get_name(col.name)
    }
    /// The cell of a column named by data (a header, an axis list read from rows), or "".
    pub fn get_name(&self, name: &str) -> &str {
        self.0.get(name).map(|s| s.as_str()).unwrap_or("")
    }
    /// The cell as a finite-or-infinite float, `None` when empty or not a number.
    pub fn f(&self, col: Col) -> Option<f64> {
        self.f_name(col.name)
    }
    /// A row of the given cells (a test's or a derived row).
    pub fn of(cells: &[(Col, &str)]) -> Rec {
        Rec(cells
            .iter()
            .map(|(c, v)| (c.name.to_string(), v.to_string()))
            .collect())
    }
    /// Sets a cell.
    pub fn set(&mut self, col: Col, value: impl Into<String>) -> &mut Rec {
        self.0.insert(col.name.to_string(), value.into());
        self
    }
    /// `f` for a column named by data.
    pub fn f_name(&self, name: &str) -> Option<f64> {
        let s = self.get_name(name);
        if s.is_empty() {
            return None;
        }
        s.parse::<f64>().ok()
    }
    pub fn ok(&self) -> bool {
        self.status() == Some(Status::Ok)
    }
    /// The row's `status` (None for a word that is not one).
    pub fn status(&self) -> Option<Status> {
        self.get(cols::STATUS).parse().ok()
    }
    /// The row's flags: `flag` is a `|`-joined list (older CSVs hold one value).
    pub fn flags(&self) -> Vec<&str> {
        self.get(cols::FLAG)
            .split('|')
            .filter(|f| !f.is_empty())
            .collect()
    }
    /// The row's flags, typed (unknown words kept).
    pub fn flag_set(&self) -> FlagSet {
        self.get(cols::FLAG).parse().unwrap_or_default()
    }
    /// Flags that every row of this row's run carries (a software adapter's `noisy`): said once
    /// for the run, not per point. Set by `Runs::load`.
    pub fn run_wide_flags(&self) -> Vec<&str> {
        self.get_name(RUN_WIDE)
            .split('|')
            .filter(|f| !f.is_empty())
            .collect()
    }
    /// The flags that single this row out: `flags` less the run-wide ones.
    pub fn marks(&self) -> Vec<&str> {
        let wide = self.run_wide_flags();
        self.flags()
            .into_iter()
            .filter(|f| !wide.contains(f))
            .collect()
    }
    /// Whether the row is singled out by a flag (drawn hollow, listed as flagged).
    pub fn flagged(&self) -> bool {
        !self.marks().is_empty()
    }
    /// Whether the image equals the ground truth within `bad_pixel_tol` (`matches_truth`, the
    /// weaker "within tolerance" label); for CSVs without it, RMSE ≤ 1e-6 with no bad pixel and
    /// no flag. `None` for rows without an image error (floors, other studies).
    pub fn within_tolerance(&self) -> Option<bool> {
        match self.get(cols::MATCHES_TRUTH) {
            "true" => Some(true),
            "false" => Some(false),
            _ => {
                let rmse = self.f(cols::RMSE)?;
                Some(
                    rmse <= OLD_EXACT_RMSE
                        && self.f(cols::BAD_PIXEL_FRAC).is_none_or(|b| b == 0.0)
                        && self.flags().is_empty(),
                )
            }
        }
    }
    /// Whether the capture is exact: no fragment lost or merged and the image equal to the truth
    /// to the f32 bound of its arithmetic. CSVs with `exact_bound` carry this judgement in
    /// `exact`; in older ones `exact` was the method's claim ("exact within capacity"), so the
    /// row is exact when the method claims it, the image is within tolerance, no flag names a
    /// lost fragment and no fragment overflowed, collided or was dropped. `None` for rows
    /// without an image error.
    pub fn exact_result(&self) -> Option<bool> {
        let within = self.within_tolerance()?;
        if self.0.contains_key(cols::EXACT_BOUND.name) {
            // Within tolerance too: rows written before `depth_ties` (the H200's compute
            // A-buffer on grass) could be exact = true with matches_truth = false.
            return Some(self.get(cols::EXACT) == "true" && within);
        }
        let claimed = self.get(cols::EXACT) != "false";
        let lost = self.flag_set().iter().any(|f| LOSS_FLAGS.contains(&f));
        let zero = |c: Col| self.f(c).is_none_or(|v| v == 0.0);
        Some(
            claimed
                && within
                && !lost
                && zero(cols::OVERFLOW_RATE)
                && zero(cols::COLLISION_RATE)
                && zero(cols::FRAGMENTS_DROPPED),
        )
    }
    /// What the method claims: every fragment captured exactly within capacity (`claims_exact`);
    /// `None` where the CSV has no such column (schema ≤ 2, whose `exact` was the claim).
    pub fn claims_exact(&self) -> Option<bool> {
        match self.get(cols::CLAIMS_EXACT) {
            "true" => Some(true),
            "false" => Some(false),
            _ => None,
        }
    }
    /// Whether the row's GPU time covers the whole frame: `gpu_time_trusted`, else the absence
    /// of the `timestamps_incomplete` flag. Untrusted times are never charted or ranked.
    pub fn time_trusted(&self) -> bool {
        match self.get(cols::GPU_TIME_TRUSTED) {
            "true" => true,
            "false" => false,
            _ => !self.flag_set().contains(Flag::TimestampsIncomplete),
        }
    }
    /// The median GPU time when it can be trusted (see `time_trusted`).
    pub fn trusted_ms(&self) -> Option<f64> {
        self.f(cols::GPU_MS_MEDIAN).filter(|_| self.time_trusted())
    }
    /// What `gpu_ms_ci_lo/hi` are: a 95 % interval of the median, or (too few samples for one)
    /// the samples' min–max range. `gpu_ms_interval` where written; else "range" when `samples`
    /// is below the fewest that a distribution-free 95 % interval needs (6).
    pub fn interval(&self) -> Interval {
        match self.get(cols::GPU_MS_INTERVAL) {
            "range" => Interval::Range(self.samples()),
            "ci95" => Interval::Ci95,
            _ => match self.samples() {
                Some(n) if mfx_stats::median_ci::lower_index(n).is_none() => {
                    Interval::Range(Some(n))
                }
                _ => Interval::Ci95,
            },
        }
    }
    /// Kept samples of the median, when written.
    pub fn samples(&self) -> Option<usize> {
        self.f(cols::SAMPLES)
            .filter(|n| *n >= 0.0)
            .map(|n| n as usize)
    }
    /// Bytes the method allocated per pixel: `bytes_per_pixel`, else bytes_allocated / pixels.
    pub fn bytes_per_pixel(&self) -> Option<f64> {
        self.f(cols::BYTES_PER_PIXEL).or_else(|| {
            let px = self.f(cols::WIDTH)? * self.f(cols::HEIGHT)?;
            (px > 0.0).then(|| self.f(cols::BYTES_ALLOCATED).map(|b| b / px))?
        })
    }
    /// The interval of the median GPU time (see `interval` for what it is), when written.
    pub fn gpu_ci(&self) -> Option<(f64, f64)> {
        Some((self.f(cols::GPU_MS_CI_LO)?, self.f(cols::GPU_MS_CI_HI)?))
    }
    pub fn is_floor(&self) -> bool {
        self.get(cols::METHOD).starts_with("floor_")
    }
    /// Method plus its non-empty axis values: one series per configuration.
    pub fn config_label(&self, axes: &[Col]) -> String {
        let mut s = self.get(cols::METHOD).to_string();
        let parts: Vec<String> = axes
            .iter()
            .filter(|a| !self.get(**a).is_empty())
            .map(|a| format!("{a}={}", self.get(*a)))
            .collect();
        if !parts.is_empty() {
            s.push_str(&format!(" ({})", parts.join(", ")));
        }
        s
    }
}

/// What a row's time interval is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interval {
    /// A 95 % confidence interval of the median.
    Ci95,
    /// Min–max of the samples (their count when known): too few for a 95 % interval.
    Range(Option<usize>),
}

impl Interval {
    /// "95 % CI" or "range (n = 3)".
    pub fn name(&self) -> String {
        match self {
            Interval::Ci95 => "95 % CI".into(),
            Interval::Range(Some(n)) => format!("range (n = {n})"),
            Interval::Range(None) => "range".into(),
        }
    }
}

/// The derived cell holding a row's run-wide flags (not a CSV column: no header names it).
const RUN_WIDE: &str = "\u{1}run_wide_flags";

/// Flags that say a fragment was lost, merged or misplaced: a row with one is never exact.
/// (`Flag::LOSS` less `precision`: older CSVs flagged non-finite output that way too.)
pub const LOSS_FLAGS: &[Flag] = &[
    Flag::Overflow,
    Flag::Collision,
    Flag::Hazard,
    Flag::LostCoplanar,
    Flag::FragmentsDiffer,
    Flag::ImageDiffers,
];

/// Older CSVs (no `matches_truth`): a row counts as exact at RMSE ≤ this, no bad pixel, no flag.
pub const OLD_EXACT_RMSE: f64 = 1e-6;

/// The rows of one or more runs.csv files (same header required).
#[derive(Clone, Debug, Default)]
pub struct Runs {
    pub header: Vec<String>,
    pub rows: Vec<Rec>,
    pub sources: Vec<PathBuf>,
}

impl Runs {
    /// Reads a runs table: `runs.csv` or `runs.parquet` (typed cells read back as the CSV's
    /// text, so both give the same rows).
    pub fn load(path: &Path) -> Result<Runs> {
        let t = mfx_table::read(path).with_context(|| format!("reading {}", path.display()))?;
        let header = t.header;
        if !header.iter().any(|h| h == cols::SCHEMA.name) {
            bail!(
                "{}: not an mfx runs table (no 'schema' column)",
                path.display()
            );
        }
        let rows = t
            .rows
            .into_iter()
            .map(|r| Rec(header.iter().cloned().zip(r).collect()))
            .collect();
        let mut runs = Runs {
            header,
            rows,
            sources: vec![path.to_path_buf()],
        };
        runs.mark_run_wide();
        Ok(runs)
    }

    /// Records on each row the flags every ok, timed row of its run carries (a run of at least
    /// two such rows): those describe the run, not a point.
    pub fn mark_run_wide(&mut self) {
        let mut by_run: BTreeMap<String, Option<Vec<String>>> = BTreeMap::new();
        let mut count: BTreeMap<String, usize> = BTreeMap::new();
        for r in &self.rows {
            if !r.ok() || r.f(cols::GPU_MS_MEDIAN).is_none() {
                continue;
            }
            let id = r.get(cols::RUN_ID).to_string();
            *count.entry(id.clone()).or_default() += 1;
            let fl: Vec<String> = r.flags().iter().map(|s| s.to_string()).collect();
            let e = by_run.entry(id).or_insert(None);
            *e = Some(match e.take() {
                None => fl,
                Some(common) => common.into_iter().filter(|f| fl.contains(f)).collect(),
            });
        }
        for r in &mut self.rows {
            let id = r.get(cols::RUN_ID).to_string();
            let wide = match (by_run.get(&id), count.get(&id)) {
                (Some(Some(c)), Some(&n)) if n >= 2 => c.join("|"),
                _ => String::new(),
            };
            r.0.insert(RUN_WIDE.to_string(), wide);
        }
    }

    /// Flags that cover every row of a run, with the run: said once in the summary.
    pub fn run_wide_flags(&self) -> Vec<(String, Vec<String>)> {
        let mut out: Vec<(String, Vec<String>)> = Vec::new();
        for r in &self.rows {
            let id = r.get(cols::RUN_ID);
            let w: Vec<String> = r.run_wide_flags().iter().map(|s| s.to_string()).collect();
            if !w.is_empty() && !out.iter().any(|(i, _)| i == id) {
                out.push((id.to_string(), w));
            }
        }
        out
    }

    /// Whether the CSV has a column (an older CSV lacks the newer ones: "not measured").
    pub fn has(&self, col: Col) -> bool {
        self.header.iter().any(|h| h == col.name)
    }

    /// How exactness is decided for this CSV, in one sentence.
    pub fn exactness_rule(&self) -> String {
        if self.header.iter().any(|h| h == cols::EXACT_BOUND.name) {
            "exact = no fragment lost or merged and the image equal to the ground truth within the f32 bound of its arithmetic (exact, exact_bound); \"within tol.\" = matches_truth only (within bad_pixel_tol)".into()
        } else if self.has(cols::MATCHES_TRUTH) {
            "exact = an exact method (exact column), matches_truth, no flag naming a lost fragment (overflow, collision, hazard, lost_coplanar, fragments_differ, image_differs) and zero overflow, collision and drop rates; \"within tol.\" = matches_truth alone".into()
        } else {
            format!(
                "exact = RMSE ≤ {OLD_EXACT_RMSE:.0e}, no bad pixel and no flag (this CSV predates the matches_truth column)"
            )
        }
    }

    /// Rows of one study kind.
    pub fn study(&self, kind: StudyKind) -> Vec<&Rec> {
        self.rows
            .iter()
            .filter(|r| r.get(cols::STUDY) == kind.name())
            .collect()
    }

    /// Rows grouped by `key`, groups in first-seen order (rows keep their order within a group).
    pub fn group_by<'a>(
        rows: impl IntoIterator<Item = &'a Rec>,
        key: impl Fn(&Rec) -> String,
    ) -> Vec<(String, Vec<&'a Rec>)> {
        let mut out: Vec<(String, Vec<&'a Rec>)> = Vec::new();
        for r in rows {
            let k = key(r);
            match out.iter_mut().find(|(g, _)| *g == k) {
                Some((_, v)) => v.push(r),
                None => out.push((k, vec![r])),
            }
        }
        out
    }

    /// `group_by` over any items (first-seen order of keys).
    pub fn group_by_owned<'a, T>(
        items: &'a [T],
        key: impl Fn(&T) -> String,
    ) -> Vec<(String, Vec<&'a T>)> {
        let mut out: Vec<(String, Vec<&'a T>)> = Vec::new();
        for t in items {
            let k = key(t);
            match out.iter_mut().find(|(g, _)| *g == k) {
                Some((_, v)) => v.push(t),
                None => out.push((k, vec![t])),
            }
        }
        out
    }

    /// Distinct values of `key` over rows, first-seen order.
    pub fn distinct_by(rows: &[&Rec], key: impl Fn(&Rec) -> String) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for r in rows {
            let k = key(r);
            if !out.contains(&k) {
                out.push(k);
            }
        }
        out
    }

    /// Distinct strings, first-seen order.
    pub fn distinct_strings<'a>(items: impl IntoIterator<Item = &'a str>) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for s in items {
            if !out.iter().any(|o| o == s) {
                out.push(s.to_string());
            }
        }
        out
    }

    /// Distinct non-empty values of a column, in first-seen order.
    pub fn distinct<'a>(rows: impl IntoIterator<Item = &'a Rec>, col: Col) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for r in rows {
            let v = r.get(col);
            if !v.is_empty() && !out.iter().any(|o| o == v) {
                out.push(v.to_string());
            }
        }
        out
    }
}

/// A row's resolution as `WxH`.
pub fn resolution(r: &Rec) -> String {
    format!("{}x{}", r.get(cols::WIDTH), r.get(cols::HEIGHT))
}

/// "adapter (backend)": the unit compared.
pub fn platform(r: &Rec) -> String {
    // Another limits profile on the same adapter is another platform (what a browser grants).
    match r.get(cols::LIMITS) {
        "" | "adapter" => format!("{} ({})", r.get(cols::ADAPTER), r.get(cols::BACKEND)),
        l => format!(
            "{} ({}, {l} limits)",
            r.get(cols::ADAPTER),
            r.get(cols::BACKEND)
        ),
    }
}

pub fn platforms(runs: &Runs) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in &runs.rows {
        let p = platform(r);
        if !out.contains(&p) {
            out.push(p);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(cells: &[(Col, &str)]) -> Rec {
        Rec::of(cells)
    }

    #[test]
    fn an_overflowing_capture_within_tolerance_is_not_exact() {
        // quads(32) at 128²: kbuffer_rmw layers=16 overflows in 27 % of pixels, max_abs_err
        // under bad_pixel_tol, so matches_truth = true; today's CSV calls the method exact.
        let k = rec(&[
            (cols::MATCHES_TRUTH, "true"),
            (cols::EXACT, "true"),
            (cols::OVERFLOW_RATE, "0.271"),
            (cols::RMSE, "3.2e-4"),
            (cols::FLAG, Flag::Overflow.name()),
        ]);
        assert_eq!(k.within_tolerance(), Some(true));
        assert_eq!(k.exact_result(), Some(false));
        // Without the flag the rate alone decides; a clean exact method stays exact.
        let mut no_flag = k.clone();
        no_flag.set(cols::FLAG, "");
        assert_eq!(no_flag.exact_result(), Some(false));
        let peel = rec(&[
            (cols::MATCHES_TRUTH, "true"),
            (cols::EXACT, "true"),
            (cols::RMSE, "3e-8"),
        ]);
        assert_eq!(peel.exact_result(), Some(true));
        // An approximate method within tolerance is not exact either.
        let bdp = rec(&[
            (cols::MATCHES_TRUTH, "true"),
            (cols::EXACT, "false"),
            (cols::RMSE, "1.1e-4"),
        ]);
        assert_eq!(bdp.exact_result(), Some(false));
        // With exact_bound (the new judgement) `exact` is read as written.
        let new = rec(&[
            (cols::MATCHES_TRUTH, "true"),
            (cols::EXACT, "false"),
            (cols::EXACT_BOUND, "1e-6"),
            (cols::RMSE, "1e-7"),
        ]);
        assert_eq!(new.exact_result(), Some(false));
        // Exact implies within tolerance, also in a CSV written when it did not.
        let tie = rec(&[
            (cols::MATCHES_TRUTH, "false"),
            (cols::EXACT, "true"),
            (cols::EXACT_BOUND, "0.18"),
            (cols::RMSE, "1e-3"),
        ]);
        assert_eq!(tie.exact_result(), Some(false));
    }

    #[test]
    fn untrusted_times_and_small_samples_are_read_with_fallbacks() {
        let r = rec(&[
            (cols::GPU_MS_MEDIAN, "3.45"),
            (cols::FLAG, Flag::TimestampsIncomplete.name()),
            (cols::SAMPLES, "3"),
        ]);
        assert!(!r.time_trusted() && r.trusted_ms().is_none());
        assert_eq!(r.interval(), Interval::Range(Some(3)));
        assert_eq!(r.interval().name(), "range (n = 3)");
        let r = rec(&[
            (cols::GPU_MS_MEDIAN, "1"),
            (cols::GPU_TIME_TRUSTED, "true"),
            (cols::SAMPLES, "6"),
        ]);
        assert!(r.time_trusted());
        assert_eq!(r.interval(), Interval::Ci95);
        let r = rec(&[(cols::GPU_MS_INTERVAL, "range"), (cols::SAMPLES, "40")]);
        assert_eq!(r.interval(), Interval::Range(Some(40)));
    }
}
