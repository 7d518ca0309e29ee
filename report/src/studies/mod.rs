//! Figures per study kind. Each module reads only the rows of its study.

pub mod methods;
pub mod shadows;

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
    if !runs.study("shadows").is_empty() {
        out.push((
            "Soft shadows (layered shadow maps vs ray tracing)".to_string(),
            shadows::figures(runs, dir)?,
        ));
    }
    Ok(out)
}
