//! The FLIP section: the run's worst points by FLIP (`flip/worst.csv`, written by the sweep with
//! the PNGs beside it), each as method image, ground truth and FLIP difference map side by side.

use schema::flip_worst as fw;
use schema::Col;
use std::path::Path;

use anyhow::{Context, Result};
use maud::{html, Markup};

use crate::cells::short;
use crate::labels::scene_name;

/// Columns of `flip/worst.csv` (PNG paths relative to the run folder).
pub use schema::flip_worst::ALL as WORST_COLUMNS;

/// The section's HTML; `report_dir` is where the page lives (image paths are made relative to
/// it). A run without `flip/worst.csv` gets one line saying so.
pub fn section(run_dir: &Path, report_dir: &Path) -> Result<Markup> {
    let csv = run_dir.join("flip").join("worst.csv");
    let head = html! { h2 id="flip" { "FLIP: the worst points" } };
    if !csv.is_file() {
        return Ok(html! {
            (head)
            p.note { "This run has no FLIP images (no flip/worst.csv in the run folder)." }
        });
    }
    let mut rdr =
        csv::Reader::from_path(&csv).with_context(|| format!("reading {}", csv.display()))?;
    let header: Vec<String> = rdr.headers()?.iter().map(String::from).collect();
    let col = |c: Col| header.iter().position(|h| h == c.name);
    let missing: Vec<&str> = WORST_COLUMNS
        .iter()
        .copied()
        .filter(|c| col(*c).is_none())
        .map(|c| c.name)
        .collect();
    if !missing.is_empty() {
        return Ok(html! {
            (head)
            p.failed {
                (csv.display().to_string()) " lacks column(s) " (missing.join(", "))
                ": FLIP images not shown."
            }
        });
    }
    // From the page (run/report/…/index.html) back to the run folder.
    let up = relative_up(run_dir, report_dir);
    let mut rows = Vec::new();
    for rec in rdr.records() {
        rows.push(rec.with_context(|| format!("reading {}", csv.display()))?);
    }
    let img = |rec: &csv::StringRecord, c: Col| {
        let p = rec.get(col(c).unwrap()).unwrap_or("");
        html! {
            @if p.is_empty() {
                td { "(none)" }
            } @else if run_dir.join(p).is_file() {
                td { img src={ (up) (p) } alt=(c.name); }
            } @else {
                td.failed { "missing: " (p) }
            }
        }
    };
    Ok(html! {
        (head)
        p.note {
            "FLIP (NVIDIA, Andersson et al. 2020) predicts the difference a viewer sees when flipping between two images: 0 none, 1 the largest. \
             Each row: the method's image, the ground truth (every fragment), and the per-pixel FLIP map in the magma colour map (black: no visible difference; yellow: large)."
        }
        table.flip id="flip-worst" {
            tr {
                th { "rank" } th { "point" } th { "FLIP mean / p99" } th { "method" }
                th { "ground truth" } th { "FLIP map" }
            }
            @for rec in &rows {
                @let get = |c: Col| rec.get(col(c).unwrap()).unwrap_or("");
                tr {
                    td { (get(fw::RANK)) }
                    td {
                        (get(fw::METHOD)) br; (scene_name(get(fw::SCENE_LABEL))) br;
                        small { (get(fw::POINT_KEY)) }
                    }
                    td {
                        (short(get(fw::FLIP_MEAN).parse().ok())) " / "
                        (short(get(fw::FLIP_P99).parse().ok()))
                    }
                    (img(rec, fw::METHOD_PNG))
                    (img(rec, fw::TRUTH_PNG))
                    (img(rec, fw::FLIP_PNG))
                }
            }
        }
    })
}

/// "../" repeated for each folder `report_dir` lies below `run_dir`.
fn relative_up(run_dir: &Path, report_dir: &Path) -> String {
    let depth = report_dir
        .strip_prefix(run_dir)
        .map(|p| p.components().count())
        .unwrap_or(1);
    "../".repeat(depth)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_worst_csv_one_line_and_with_it_three_images_per_row() {
        let d_tmp = tempfile::Builder::new()
            .prefix("mfx-flip-")
            .tempdir()
            .unwrap();
        let d = d_tmp.path().to_path_buf();
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(d.join("flip")).unwrap();
        let h = section(&d, &d.join("report")).unwrap().into_string();
        assert!(h.contains("has no FLIP images"), "{h}");
        for f in ["m.png", "t.png", "f.png"] {
            std::fs::write(d.join("flip").join(f), b"png").unwrap();
        }
        std::fs::write(
            d.join("flip/worst.csv"),
            format!(
                "{}\n1,methods|q|64x64|wboit|,wboit,q(d=8),0.21,0.8,flip/m.png,flip/t.png,flip/f.png\n",
                WORST_COLUMNS.map(|c| c.name).join(",")
            ),
        )
        .unwrap();
        let h = section(&d, &d.join("report")).unwrap().into_string();
        assert_eq!(h.matches("<img src=\"../flip/").count(), 3, "{h}");
        assert!(h.contains("0.21 / 0.8"), "{h}");
    }
}
