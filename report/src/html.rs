//! The report page: run metadata, the summary (the same text as `summary_text`), flagged points,
//! figures and tables per study, FLIP images, every row, and every skipped/failed row.

use schema::{cols, Status};
use std::fmt::Write;

use crate::cells::{esc, exact_cell, short, time_cell};
use crate::charts::Figure;
use crate::labels::scene_name;
use mfx_analysis::data::{Rec, Runs};

const STYLE: &str = "body{font-family:sans-serif;max-width:1400px;margin:2em auto;color:#222;padding:0 1em}\
table{border-collapse:collapse;margin:1em 0;font-size:13px}td,th{border:1px solid #ccc;padding:3px 7px;text-align:left}\
th{background:#f3f3f3}caption{text-align:left;color:#555;padding:4px 0}figure{margin:1.5em 0}\
img{max-width:100%;border:1px solid #ddd}figcaption{color:#555;font-size:13px;max-width:1100px}\
.failed{color:#b00}.skipped{color:#a60}tr.flagged td{background:#fff6e6}tr.floor td{color:#666;font-style:italic}\
p.note{color:#555;font-size:14px;margin:.4em 0}table.verdict td{vertical-align:top;max-width:330px}details{margin:.5em 0}summary{cursor:pointer;color:#245}\
.flip td{vertical-align:top}.flip img{width:256px;image-rendering:pixelated}";

pub fn page(
    runs: &Runs,
    sections: &[(String, Vec<Figure>)],
    extra_html: &str,
    flip_html: &str,
) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>mfx report</title><style>{STYLE}</style></head><body><h1>mfx report</h1>"
    );
    // Metadata: one line per distinct machine/run.
    h.push_str("<h2>Runs</h2><table id=\"runs\"><tr><th>run_id</th><th>suite</th><th>git_rev</th><th>adapter</th><th>backend</th><th>device type</th><th>driver</th><th>rows ok / skipped / failed</th></tr>");
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in &runs.rows {
        let k = (
            r.get(cols::RUN_ID).to_string(),
            r.get(cols::ADAPTER).to_string() + r.get(cols::BACKEND),
        );
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    for (run, ad) in &keys {
        let rs: Vec<&Rec> = runs
            .rows
            .iter()
            .filter(|r| {
                r.get(cols::RUN_ID) == run
                    && format!("{}{}", r.get(cols::ADAPTER), r.get(cols::BACKEND)) == *ad
            })
            .collect();
        let f = rs[0];
        let count = |s: Status| rs.iter().filter(|r| r.status() == Some(s)).count();
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} {}</td><td>{} / {} / {}</td></tr>",
            esc(run),
            esc(f.get(cols::SUITE)),
            esc(f.get(cols::GIT_REV)),
            esc(f.get(cols::ADAPTER)),
            esc(f.get(cols::BACKEND)),
            esc(f.get(cols::DEVICE_TYPE)),
            esc(f.get(cols::DRIVER)),
            esc(f.get(cols::DRIVER_INFO)),
            count(Status::Ok),
            count(Status::Skipped),
            count(Status::Failed)
        );
    }
    h.push_str("</table>");
    // What the run found, as a verdict table first (the same verdicts `mfx sweep` prints).
    h.push_str(&crate::summary::summary_html(runs));
    if !sections.is_empty() {
        h.push_str("<h2>Contents</h2><ul>");
        for (i, (title, _)) in sections.iter().enumerate() {
            let _ = write!(h, "<li><a href=\"#s{i}\">{}</a></li>", esc(title));
        }
        h.push_str("<li><a href=\"#flip\">FLIP: the worst points</a></li><li><a href=\"#flagged-points\">Flagged points</a></li><li><a href=\"#rows\">Rows</a></li></ul>");
    }
    for (i, (title, figs)) in sections.iter().enumerate() {
        // Each section folds: the page opens on the verdict, not on 45 000 px of charts.
        let charts = figs.iter().filter(|f| f.is_chart()).count();
        let _ = write!(
            h,
            "<h2 id=\"s{i}\">{}</h2><details><summary>{charts} chart(s), {} table(s) and note(s)</summary>",
            esc(title),
            figs.len() - charts
        );
        for f in figs {
            if let Some(n) = &f.note {
                let _ = write!(
                    h,
                    "<p class=\"note\"><b>{}</b>: {}</p>",
                    esc(&f.title),
                    esc(n)
                );
            } else if let Some(block) = &f.html {
                // A table's caption says how to read it, as a chart's does.
                let cap = if f.caption.is_empty() {
                    String::new()
                } else {
                    format!("<p class=\"note\">{}</p>", esc(&f.caption))
                };
                let _ = write!(
                    h,
                    "<details><summary>{}</summary>{cap}{block}</details>",
                    esc(&f.title)
                );
            } else {
                // The page shows the SVG (vector, small enough to commit with reference runs);
                // the PNG beside it is for slides and is not tracked under results/reference/.
                let _ = write!(
                    h,
                    "<figure><img src=\"{0}.svg\" alt=\"{1}\"><figcaption>{1}. {2} (<a href=\"{0}.png\">PNG</a>, <a href=\"{0}.pdf\">PDF</a>)</figcaption></figure>",
                    esc(&f.stem),
                    esc(&f.title),
                    esc(&f.caption)
                );
            }
        }
        h.push_str("</details>");
    }
    h.push_str(extra_html);
    h.push_str(flip_html);
    flagged_table(&mut h, runs);
    rows_table(&mut h, runs);
    let bad: Vec<&Rec> = runs.rows.iter().filter(|r| !r.ok()).collect();
    let _ = write!(h, "<h2>Skipped and failed rows ({})</h2><table id=\"notok\"><tr><th>status</th><th>point</th><th>reason</th></tr>", bad.len());
    for r in bad {
        let _ = write!(
            h,
            "<tr class=\"{0}\"><td>{0}</td><td>{1}</td><td>{2}</td></tr>",
            esc(r.get(cols::STATUS)),
            esc(r.get(cols::POINT_KEY)),
            esc(r.get(cols::REASON))
        );
    }
    h.push_str("</table></body></html>\n");
    h
}

/// Every flagged ok row, with its flags and notes.
fn flagged_table(h: &mut String, runs: &Runs) {
    let rows: Vec<&Rec> = runs.rows.iter().filter(|r| r.ok() && r.flagged()).collect();
    let _ = write!(
        h,
        "<h2 id=\"flagged-points\">Flagged points ({})</h2>",
        rows.len()
    );
    if rows.is_empty() {
        h.push_str("<p class=\"note\">No ok row carries a flag.</p>");
        return;
    }
    h.push_str("<details><summary>Every flagged row</summary><p class=\"note\">A flag names a known failure mode the harness detected (overflow, hazard, collision, precision, lost_coplanar, fragments_differ, image_differs, timestamps_incomplete, noisy, throttled); these points are drawn hollow in the charts. A flag that every timed row of a run carries is said once in the verdict and not marked per point.</p>\
        <table id=\"flagged\"><tr><th>flag</th><th>study</th><th>scene</th><th>resolution</th><th>point</th><th>GPU ms</th><th>RMSE</th><th>notes</th></tr>");
    for r in rows {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}x{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&r.flags().join(", ")),
            esc(r.get(cols::STUDY)),
            esc(&scene_name(r.get(cols::SCENE_LABEL))),
            r.get(cols::WIDTH),
            r.get(cols::HEIGHT),
            esc(&point_key_tail(r)),
            time_cell(r),
            short(r.f(cols::RMSE)),
            esc(r.get(cols::NOTES))
        );
    }
    h.push_str("</table></details>");
}

fn rows_table(h: &mut String, runs: &Runs) {
    let flip = runs.has(cols::FLIP_MEAN);
    let _ = write!(
        h,
        "<h2 id=\"rows-h\">Rows</h2><details><summary>Every ok row</summary><table id=\"rows\"><tr><th>adapter (backend)</th><th>study</th><th>scene</th><th>resolution</th><th>method</th><th>axes</th>\
         <th>GPU ms [95 % CI] or (range, n)</th><th>× floor</th><th>bytes/px</th><th>RMSE</th>{}<th>max abs err</th><th>exact</th><th>flag</th></tr>",
        if flip { "<th>FLIP mean</th><th>FLIP p99</th>" } else { "" }
    );
    for r in runs.rows.iter().filter(|r| r.ok()) {
        let _ = write!(
            h,
            "<tr><td>{} ({})</td><td>{}</td><td>{}</td><td>{}x{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>{}<td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(r.get(cols::ADAPTER)),
            esc(r.get(cols::BACKEND)),
            esc(r.get(cols::STUDY)),
            esc(r.get(cols::SCENE_LABEL)),
            r.get(cols::WIDTH),
            r.get(cols::HEIGHT),
            esc(r.get(cols::METHOD)),
            esc(&point_key_axes(r)),
            time_cell(r),
            short(r.f(cols::X_FLOOR).filter(|_| r.time_trusted())),
            short(r.bytes_per_pixel()),
            short(r.f(cols::RMSE)),
            if flip {
                format!("<td>{}</td><td>{}</td>", short(r.f(cols::FLIP_MEAN)), short(r.f(cols::FLIP_P99)))
            } else {
                String::new()
            },
            short(r.f(cols::MAX_ABS_ERR)),
            exact_cell(r),
            esc(&r.flags().join(", "))
        );
    }
    h.push_str("</table></details>");
}

/// "method axes" of a row's point key (its raw text if it does not parse).
fn point_key_tail(r: &Rec) -> String {
    match r.get(cols::POINT_KEY).parse::<schema::PointKey>() {
        Ok(k) => format!("{} {}", k.method, k.axes),
        Err(_) => r.get(cols::POINT_KEY).to_string(),
    }
}

/// The axes field of a row's point key (empty if it does not parse).
fn point_key_axes(r: &Rec) -> String {
    r.get(cols::POINT_KEY)
        .parse::<schema::PointKey>()
        .map(|k| k.axes)
        .unwrap_or_default()
}
