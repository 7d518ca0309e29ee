//! Figures per study kind. Each module reads only the rows of its study. `PAGES` is the table of
//! what a report can hold: a study (or any other section, such as a reproduction of published
//! figures) adds its row there, and `all_figures` walks the table in order.

pub mod buckets;
pub mod deferred;
pub mod geometry;
pub mod limits;
pub mod methods;
pub mod prepass;
pub mod scaling;
pub mod shadows;
pub mod stability;
pub mod tail;
pub mod views;

use schema::StudyKind;
use std::path::Path;

use anyhow::Result;

use crate::charts::Figure;
use mfx_analysis::data::Runs;

/// One section of the report: its heading, whether the runs hold anything for it, and how its
/// figures are drawn into a folder. A section whose figures come back empty is left out.
pub struct StudyPage {
    pub heading: &'static str,
    pub applies: fn(&Runs) -> bool,
    pub figures: fn(&Runs, &Path) -> Result<Vec<Figure>>,
    /// Reads every platform's rows of a merged CSV at once (the limits table sets a profile's
    /// rows beside the adapter's own); other pages draw one platform at a time.
    pub across_platforms: bool,
}

fn has(runs: &Runs, study: StudyKind) -> bool {
    !runs.study(study).is_empty()
}

/// Every section, in page order.
pub const PAGES: &[StudyPage] = &[
    StudyPage {
        heading: "Multi-fragment methods",
        applies: |r| has(r, StudyKind::Methods),
        figures: |r, d| {
            Ok(methods::figures(r, d)?
                .into_iter()
                .chain(buckets::figures(r, d)?)
                .collect())
        },
        across_platforms: false,
    },
    StudyPage {
        heading: "Fits a browser? (limits profiles)",
        applies: limits::applies,
        figures: limits::figures,
        across_platforms: true,
    },
    StudyPage {
        heading: "How cost grows (scaling)",
        applies: scaling::applies,
        figures: scaling::figures,
        across_platforms: false,
    },
    StudyPage {
        heading: "Effects and stability",
        applies: |r| has(r, StudyKind::Stability) || has(r, StudyKind::Methods),
        figures: stability::figures,
        across_platforms: false,
    },
    StudyPage {
        heading: "Views that move (camera paths: flicker, popping, time per view)",
        applies: |r| has(r, StudyKind::Views),
        figures: views::figures,
        across_platforms: false,
    },
    StudyPage {
        heading: "Geometry feeding (Bavoil ch. 3)",
        applies: |r| has(r, StudyKind::Geometry),
        figures: geometry::figures,
        across_platforms: false,
    },
    StudyPage {
        heading: "Soft shadows (layered shadow maps vs ray tracing)",
        applies: |r| has(r, StudyKind::Shadows),
        figures: shadows::figures,
        across_platforms: false,
    },
    StudyPage {
        heading: "Deferred shading (tiles, classification, CPU tiles)",
        applies: |r| has(r, StudyKind::Deferred),
        figures: deferred::figures,
        across_platforms: false,
    },
    StudyPage {
        heading: "Light pre-pass (and the light buffer on CPU cores)",
        applies: |r| has(r, StudyKind::Prepass),
        figures: prepass::figures,
        across_platforms: false,
    },
    StudyPage {
        heading: "Frame-time tail and throughput (every study)",
        applies: tail::applies,
        figures: tail::figures,
        across_platforms: false,
    },
];

/// (heading, figures) for every section of `PAGES` the runs hold something for.
pub fn all_figures(runs: &Runs, dir: &Path) -> Result<Vec<(String, Vec<Figure>)>> {
    figures_of(runs, dir, |_| true)
}

/// The pages `keep` selects (e.g. one platform's, or those read across platforms).
pub fn figures_of(
    runs: &Runs,
    dir: &Path,
    keep: impl Fn(&StudyPage) -> bool,
) -> Result<Vec<(String, Vec<Figure>)>> {
    let mut out = Vec::new();
    for page in PAGES {
        if !keep(page) || !(page.applies)(runs) {
            continue;
        }
        let figs = (page.figures)(runs, dir)?;
        if !figs.is_empty() {
            out.push((page.heading.to_string(), figs));
        }
    }
    Ok(out)
}
