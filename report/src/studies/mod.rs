//! Figures per study kind. Each module reads only the rows of its study.

pub mod buckets;
pub mod deferred;
pub mod geometry;
pub mod methods;
pub mod prepass;
pub mod scaling;
pub mod shadows;
pub mod stability;

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
            methods::figures(runs, dir)?
                .into_iter()
                .chain(buckets::figures(runs, dir)?)
                .collect(),
        ));
    }
    if scaling::applies(runs) {
        out.push((
            "How cost grows (scaling)".to_string(),
            scaling::figures(runs, dir)?,
        ));
    }
    if !runs.study("stability").is_empty() || !runs.study("methods").is_empty() {
        let figs = stability::figures(runs, dir)?;
        if !figs.is_empty() {
            out.push(("Effects and stability".to_string(), figs));
        }
    }
    if !runs.study("geometry").is_empty() {
        out.push((
            "Geometry feeding (Bavoil ch. 3)".to_string(),
            geometry::figures(runs, dir)?,
        ));
    }
    if !runs.study("shadows").is_empty() {
        out.push((
            "Soft shadows (layered shadow maps vs ray tracing)".to_string(),
            shadows::figures(runs, dir)?,
        ));
    }
    if !runs.study("deferred").is_empty() {
        out.push((
            "Deferred shading (tiles, classification, CPU tiles)".to_string(),
            deferred::figures(runs, dir)?,
        ));
    }
    if !runs.study("prepass").is_empty() {
        out.push((
            "Light pre-pass (and the light buffer on CPU cores)".to_string(),
            prepass::figures(runs, dir)?,
        ));
    }
    Ok(out)
}
