//! Figures per study kind. Each module reads only the rows of its study.

pub mod methods;

use std::path::Path;

use anyhow::Result;

use crate::charts::Figure;
use crate::data::Runs;

/// (heading, figures) for every study present in the runs.
pub fn all_figures(runs: &Runs, dir: &Path) -> Result<Vec<(String, Vec<Figure>)>> {
    let mut out = Vec::new();
    if !runs.study("methods").is_empty() {
        out.push((
            "Multi-fragment methods".to_string(),
            methods::figures(runs, dir)?,
        ));
    }
    Ok(out)
}
