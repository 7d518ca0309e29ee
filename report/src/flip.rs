//! The FLIP section: the run's worst points by FLIP (`flip/worst.csv`, written by the sweep with
//! the PNGs beside it), each as method image, ground truth and FLIP difference map side by side.

use schema::flip_worst as fw;
use schema::Col;
use std::fmt::Write;
use std::path::Path;

use anyhow::{Context, Result};

use crate::cells::{esc, short};
use crate::labels::scene_name;

/// Columns of `flip/worst.csv` (PNG paths relative to the run folder).
pub use schema::flip_worst::ALL as WORST_COLUMNS;

/// The section's HTML; `report_dir` is where the page lives (image paths are made relative to
/// it). A run without `flip/worst.csv` gets one line saying so.
pub fn section(run_dir: &Path, report_dir: &Path) -> Result<String> {
    let mut h = String::from("<h2 id=\"flip\">FLIP: the worst points</h2>");
    let csv = run_dir.join("flip").join("worst.csv");
    if !csv.is_file() {
        h.push_str(
            "<p class=\"note\">This run has no FLIP images (no flip/worst.csv in the run folder).</p>",
        );
        return Ok(h);
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
        let _ = write!(
            h,
            "<p class=\"failed\">{} lacks column(s) {}: FLIP images not shown.</p>",
            esc(&csv.display().to_string()),
            esc(&missing.join(", "))
        );
        return Ok(h);
    }
    // From the page (run/report/…/index.html) back to the run folder.
    let up = relative_up(run_dir, report_dir);
    h.push_str(
        "<p class=\"note\">FLIP (NVIDIA, Andersson et al. 2020) predicts the difference a viewer sees when flipping between two images: 0 none, 1 the largest. \
         Each row: the method's image, the ground truth (every fragment), and the per-pixel FLIP map in the magma colour map (black: no visible difference; yellow: large).</p>\
         <table class=\"flip\" id=\"flip-worst\"><tr><th>rank</th><th>point</th><th>FLIP mean / p99</th><th>method</th><th>ground truth</th><th>FLIP map</th></tr>",
    );
    for rec in rdr.records() {
        let rec = rec.with_context(|| format!("reading {}", csv.display()))?;
        let get = |c: Col| rec.get(col(c).unwrap()).unwrap_or("");
        let img = |c: Col| {
            let p = get(c);
            if p.is_empty() {
                "<td>(none)</td>".to_string()
            } else if run_dir.join(p).is_file() {
                format!(
                    "<td><img src=\"{}\" alt=\"{}\"></td>",
                    esc(&format!("{up}{p}")),
                    esc(c.name)
                )
            } else {
                format!("<td class=\"failed\">missing: {}</td>", esc(p))
            }
        };
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}<br>{}<br><small>{}</small></td><td>{} / {}</td>{}{}{}</tr>",
            esc(get(fw::RANK)),
            esc(get(fw::METHOD)),
            esc(&scene_name(get(fw::SCENE_LABEL))),
            esc(get(fw::POINT_KEY)),
            short(get(fw::FLIP_MEAN).parse().ok()),
            short(get(fw::FLIP_P99).parse().ok()),
            img(fw::METHOD_PNG),
            img(fw::TRUTH_PNG),
            img(fw::FLIP_PNG)
        );
    }
    h.push_str("</table>");
    Ok(h)
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
        let h = section(&d, &d.join("report")).unwrap();
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
        let h = section(&d, &d.join("report")).unwrap();
        assert_eq!(h.matches("<img src=\"../flip/").count(), 3, "{h}");
        assert!(h.contains("0.21 / 0.8"), "{h}");
    }
}
