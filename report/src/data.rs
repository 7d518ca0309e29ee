//! Reading runs.csv: rows as column → text maps, with typed accessors.

use schema::{cols, Col, FlagSet, Status};
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
    /// `f` for a column named by data.
    pub fn f_name(&self, name: &str) -> Option<f64> {
        let s = self.get_name(name);
        if s.is_empty() {
            return None;
        }
        s.parse::<f64>().ok()
    }
    pub fn ok(&self) -> bool {
        self.get(cols::STATUS).parse::<Status>() == Ok(Status::Ok)
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
    pub fn flagged(&self) -> bool {
        !self.flags().is_empty()
    }
    /// Whether the image equals the ground truth: `matches_truth` where the CSV has it; for older
    /// CSVs, RMSE ≤ 1e-6 with no bad pixel and no flag (see `Runs::exactness_rule`). `None` for
    /// rows without an image error (floors, other studies).
    pub fn exact_result(&self) -> Option<bool> {
        match self.get(cols::MATCHES_TRUTH) {
            "true" => Some(true),
            "false" => Some(false),
            _ => {
                let rmse = self.f(cols::RMSE)?;
                Some(
                    rmse <= OLD_EXACT_RMSE
                        && self.f(cols::BAD_PIXEL_FRAC).is_none_or(|b| b == 0.0)
                        && !self.flagged(),
                )
            }
        }
    }
    /// Bytes the method allocated per pixel: `bytes_per_pixel`, else bytes_allocated / pixels.
    pub fn bytes_per_pixel(&self) -> Option<f64> {
        self.f(cols::BYTES_PER_PIXEL).or_else(|| {
            let px = self.f(cols::WIDTH)? * self.f(cols::HEIGHT)?;
            (px > 0.0).then(|| self.f(cols::BYTES_ALLOCATED).map(|b| b / px))?
        })
    }
    /// The 95 % confidence interval of the median GPU time, when the CSV has one.
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
    pub fn load(path: &Path) -> Result<Runs> {
        let mut rdr =
            csv::Reader::from_path(path).with_context(|| format!("reading {}", path.display()))?;
        let header: Vec<String> = rdr
            .headers()
            .with_context(|| format!("{}: no header", path.display()))?
            .iter()
            .map(String::from)
            .collect();
        if !header.iter().any(|h| h == cols::SCHEMA.name) {
            bail!(
                "{}: not an mfx runs.csv (no 'schema' column)",
                path.display()
            );
        }
        let mut rows = Vec::new();
        for (i, rec) in rdr.records().enumerate() {
            let rec = rec.with_context(|| format!("{}: row {}", path.display(), i + 2))?;
            rows.push(Rec(header
                .iter()
                .cloned()
                .zip(rec.iter().map(String::from))
                .collect()));
        }
        Ok(Runs {
            header,
            rows,
            sources: vec![path.to_path_buf()],
        })
    }

    /// Whether the CSV has a column (an older CSV lacks the newer ones: "not measured").
    pub fn has(&self, col: Col) -> bool {
        self.header.iter().any(|h| h == col.name)
    }

    /// How exactness is decided for this CSV, in one sentence.
    pub fn exactness_rule(&self) -> String {
        if self.has(cols::MATCHES_TRUTH) {
            "exact = matches_truth (the image equals the ground truth within bad_pixel_tol everywhere)".into()
        } else {
            format!(
                "exact = RMSE ≤ {OLD_EXACT_RMSE:.0e}, no bad pixel and no flag (this CSV predates the matches_truth column)"
            )
        }
    }

    /// Rows of one study kind.
    pub fn study(&self, kind: &str) -> Vec<&Rec> {
        self.rows
            .iter()
            .filter(|r| r.get(cols::STUDY) == kind)
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
