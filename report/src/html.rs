//! The report page: run metadata, the summary (the same text as `summary_text`), flagged points,
//! figures and tables per study, FLIP images, every row, and every skipped/failed row. Written
//! through maud: every `(value)` is escaped by the template.

use maud::{html, Markup, PreEscaped, DOCTYPE};
use schema::{cols, Status};

use crate::cells::{exact_cell, short, time_cell};
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

/// The page: the runs, the verdict, the study sections, then `extra` (the sections other
/// modules wrote: platforms, reproduction, bounds, FLIP) and the row tables.
pub fn page(runs: &Runs, sections: &[(String, Vec<Figure>)], extra: &[Markup]) -> String {
    let bad: Vec<&Rec> = runs.rows.iter().filter(|r| !r.ok()).collect();
    html! {
        (DOCTYPE)
        html {
            head { meta charset="utf-8"; title { "mfx report" } style { (PreEscaped(STYLE)) } }
            body {
                h1 { "mfx report" }
                (runs_table(runs))
                // What the run found, as a verdict table first (the verdicts `mfx sweep` prints).
                (crate::summary::summary_markup(runs))
                @if !sections.is_empty() {
                    h2 { "Contents" }
                    ul {
                        @for (i, (title, _)) in sections.iter().enumerate() {
                            li { a href={ "#s" (i) } { (title) } }
                        }
                        li { a href="#flip" { "FLIP: the worst points" } }
                        li { a href="#flagged-points" { "Flagged points" } }
                        li { a href="#rows" { "Rows" } }
                    }
                }
                @for (i, (title, figs)) in sections.iter().enumerate() {
                    (section(i, title, figs))
                }
                @for e in extra { (e) }
                (flagged_table(runs))
                (rows_table(runs))
                h2 { "Skipped and failed rows (" (bad.len()) ")" }
                table id="notok" {
                    tr { th { "status" } th { "point" } th { "reason" } }
                    @for r in &bad {
                        tr class=(r.get(cols::STATUS)) {
                            td { (r.get(cols::STATUS)) }
                            td { (r.get(cols::POINT_KEY)) }
                            td { (r.get(cols::REASON)) }
                        }
                    }
                }
            }
        }
    }
    .into_string()
        + "\n"
}

/// One line per distinct run and platform.
fn runs_table(runs: &Runs) -> Markup {
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
    html! {
        h2 { "Runs" }
        table id="runs" {
            tr {
                th { "run_id" } th { "suite" } th { "git_rev" } th { "adapter" } th { "backend" }
                th { "device type" } th { "driver" } th { "rows ok / skipped / failed" }
            }
            @for (run, ad) in &keys {
                @let rs: Vec<&Rec> = runs.rows.iter().filter(|r| {
                    r.get(cols::RUN_ID) == run
                        && format!("{}{}", r.get(cols::ADAPTER), r.get(cols::BACKEND)) == *ad
                }).collect();
                @let f = rs[0];
                @let count = |s: Status| rs.iter().filter(|r| r.status() == Some(s)).count();
                tr {
                    td { (run) }
                    td { (f.get(cols::SUITE)) }
                    td { (f.get(cols::GIT_REV)) }
                    td { (f.get(cols::ADAPTER)) }
                    td { (f.get(cols::BACKEND)) }
                    td { (f.get(cols::DEVICE_TYPE)) }
                    td { (f.get(cols::DRIVER)) " " (f.get(cols::DRIVER_INFO)) }
                    td { (count(Status::Ok)) " / " (count(Status::Skipped)) " / " (count(Status::Failed)) }
                }
            }
        }
    }
}

/// One study's section, folded: the page opens on the verdict, not on 45 000 px of charts.
fn section(i: usize, title: &str, figs: &[Figure]) -> Markup {
    let charts = figs.iter().filter(|f| f.is_chart()).count();
    html! {
        h2 id={ "s" (i) } { (title) }
        details {
            summary { (charts) " chart(s), " (figs.len() - charts) " table(s) and note(s)" }
            @for f in figs {
                @if let Some(n) = &f.note {
                    p.note { b { (f.title) } ": " (n) }
                } @else if let Some(block) = &f.html {
                    // A table's caption says how to read it, as a chart's does.
                    details {
                        summary { (f.title) }
                        @if !f.caption.is_empty() { p.note { (f.caption) } }
                        (block)
                    }
                } @else {
                    // The page shows the SVG (vector, small enough to commit with reference
                    // runs); the PNG is for slides, the PDF for papers.
                    figure {
                        img src={ (f.stem) ".svg" } alt=(f.title);
                        figcaption {
                            (f.title) ". " (f.caption) " ("
                            a href={ (f.stem) ".png" } { "PNG" } ", "
                            a href={ (f.stem) ".pdf" } { "PDF" } ")"
                        }
                    }
                }
            }
        }
    }
}

/// Every flagged ok row, with its flags and notes.
fn flagged_table(runs: &Runs) -> Markup {
    let rows: Vec<&Rec> = runs.rows.iter().filter(|r| r.ok() && r.flagged()).collect();
    html! {
        h2 id="flagged-points" { "Flagged points (" (rows.len()) ")" }
        @if rows.is_empty() {
            p.note { "No ok row carries a flag." }
        } @else {
            details {
                summary { "Every flagged row" }
                p.note { "A flag names a known failure mode the harness detected (overflow, hazard, collision, precision, lost_coplanar, fragments_differ, image_differs, timestamps_incomplete, noisy, throttled); these points are drawn hollow in the charts. A flag that every timed row of a run carries is said once in the verdict and not marked per point." }
                table id="flagged" {
                    tr {
                        th { "flag" } th { "study" } th { "scene" } th { "resolution" } th { "point" }
                        th { "GPU ms" } th { "RMSE" } th { "notes" }
                    }
                    @for r in &rows {
                        tr {
                            td { (r.flags().join(", ")) }
                            td { (r.get(cols::STUDY)) }
                            td { (scene_name(r.get(cols::SCENE_LABEL))) }
                            td { (r.get(cols::WIDTH)) "x" (r.get(cols::HEIGHT)) }
                            td { (point_key_tail(r)) }
                            td { (time_cell(r)) }
                            td { (short(r.f(cols::RMSE))) }
                            td { (r.get(cols::NOTES)) }
                        }
                    }
                }
            }
        }
    }
}

fn rows_table(runs: &Runs) -> Markup {
    let flip = runs.has(cols::FLIP_MEAN);
    html! {
        h2 id="rows-h" { "Rows" }
        details {
            summary { "Every ok row" }
            table id="rows" {
                tr {
                    th { "adapter (backend)" } th { "study" } th { "scene" } th { "resolution" }
                    th { "method" } th { "axes" } th { "GPU ms [95 % CI] or (range, n)" }
                    th { "× floor" } th { "bytes/px" } th { "RMSE" }
                    @if flip { th { "FLIP mean" } th { "FLIP p99" } }
                    th { "max abs err" } th { "exact" } th { "flag" }
                }
                @for r in runs.rows.iter().filter(|r| r.ok()) {
                    tr {
                        td { (r.get(cols::ADAPTER)) " (" (r.get(cols::BACKEND)) ")" }
                        td { (r.get(cols::STUDY)) }
                        td { (r.get(cols::SCENE_LABEL)) }
                        td { (r.get(cols::WIDTH)) "x" (r.get(cols::HEIGHT)) }
                        td { (r.get(cols::METHOD)) }
                        td { (point_key_axes(r)) }
                        td { (time_cell(r)) }
                        td { (short(r.f(cols::X_FLOOR).filter(|_| r.time_trusted()))) }
                        td { (short(r.bytes_per_pixel())) }
                        td { (short(r.f(cols::RMSE))) }
                        @if flip {
                            td { (short(r.f(cols::FLIP_MEAN))) }
                            td { (short(r.f(cols::FLIP_P99))) }
                        }
                        td { (short(r.f(cols::MAX_ABS_ERR))) }
                        td { (exact_cell(r)) }
                        td { (r.flags().join(", ")) }
                    }
                }
            }
        }
    }
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
