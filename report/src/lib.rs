//! CSV → plots → HTML. Never touches a GPU: a report can be built from CSVs made on other
//! machines, merged, or years old. `build(dir)` reads `dir/runs.csv` and writes
//! `dir/report/index.html` with PNG, SVG and PDF figures (and their layout records) beside it,
//! and `dir/report/latex/` (numbers.tex and booktabs tables, `latex.rs`);
//! `summary_text` is the run's findings as text (the page's summary section, and what
//! `mfx sweep` prints at its end).

pub mod ab;
pub mod bounds;
pub mod cells;
pub mod charts;
pub mod compare;
pub mod flip;
pub mod html;
pub mod labels;
pub mod latex;
pub mod pareto;
pub mod points;
pub mod reproduction;
pub mod studies;
pub mod summary;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// The rows, read by `mfx_analysis` (kept under this name for the pages that say `crate::data`).
pub use mfx_analysis::data;
pub use mfx_analysis::{Rec, Runs};
pub use summary::summary_text;

/// Builds the report of a run folder (its `runs.csv` or `runs.parquet`); returns the page's path.
pub fn build(dir: &Path, baseline: Option<&str>) -> Result<PathBuf> {
    // runs.csv, else runs.parquet (a run folder unpacked from a bundle holds only the latter).
    let table = mfx_table::locate(dir)?;
    let runs = Runs::load(&table)?;
    let out = dir.join("report");
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    clear_charts(&out)?;
    // Each study's figures read one platform's rows: a merged CSV (several adapters or backends)
    // gets one set per platform, in its own subfolder, so no chart mixes two machines' rows.
    let plats = mfx_analysis::data::platforms(&runs);
    let mut sections = Vec::new();
    if plats.len() < 2 {
        sections = studies::all_figures(&runs, &out)?;
    } else {
        for (i, p) in plats.iter().enumerate() {
            let mut one = runs.clone();
            one.rows.retain(|r| mfx_analysis::data::platform(r) == *p);
            let sub = format!("platform{i}");
            let dir = out.join(&sub);
            std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
            for (title, figs) in studies::figures_of(&one, &dir, |p| !p.across_platforms)? {
                let figs = figs
                    .into_iter()
                    .map(|mut f| {
                        if f.is_chart() {
                            f.stem = format!("{sub}/{}", f.stem);
                        }
                        f.title = format!("{} [{p}]", f.title);
                        f
                    })
                    .collect();
                sections.push((format!("{title} — {p}"), figs));
            }
        }
        sections.extend(studies::figures_of(&runs, &out, |p| p.across_platforms)?);
    }
    // More than one adapter or backend (a merged CSV): compare them.
    let mut extra = Vec::new();
    if let Some(c) = compare::compare(&runs, dir, &out, baseline)? {
        sections.push(("Adapters and backends".to_string(), c.figures));
        extra.push(c.html);
    }
    // The sources' published figures beside ours (empty unless a seeds-* suite ran); its HTML
    // is reproduction.rs's own, escaped there.
    let bands = reproduction::Bands::for_run(dir)?;
    extra.push(maud::PreEscaped(reproduction::section_with(&runs, &bands)));
    let md = reproduction::markdown_with(&runs, &bands);
    if !md.is_empty() {
        let p = out.join("reproduction.md");
        std::fs::write(&p, md).with_context(|| format!("writing {}", p.display()))?;
    }
    // What bounds each point (slowest pass, floor, bandwidth): also as markdown for RUN.md.
    extra.push(bounds::section(&runs));
    let md = bounds::markdown(&runs);
    if !md.is_empty() {
        let p = out.join("bounds.md");
        std::fs::write(&p, md).with_context(|| format!("writing {}", p.display()))?;
    }
    // The run for a paper: numbers.tex, booktabs tables (the PDF charts sit beside the SVGs).
    latex::write(&runs, &bands, &out)?;
    extra.push(flip::section(dir, &out)?);
    let page = html::page(&runs, &sections, &extra);
    let path = out.join("index.html");
    std::fs::write(&path, page).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

/// Removes the charts an earlier build left in the report folder (names change when a chart's
/// rules do), so the folder holds only what this build drew. Only chart files are touched.
fn clear_charts(out: &Path) -> Result<()> {
    for e in std::fs::read_dir(out).with_context(|| format!("reading {}", out.display()))? {
        let p = e?.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if p.is_dir() && name.starts_with("platform") {
            clear_charts(&p)?;
        } else if [".png", ".svg", ".pdf", ".layout.json"]
            .iter()
            .any(|x| name.ends_with(x))
        {
            std::fs::remove_file(&p).with_context(|| format!("removing {}", p.display()))?;
        }
    }
    Ok(())
}
