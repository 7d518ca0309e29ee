//! The report page: run metadata, figures, a per-row summary, and every skipped/failed row.

use std::fmt::Write;

use crate::charts::Figure;
use crate::data::{Rec, Runs};

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

pub fn page(runs: &Runs, sections: &[(String, Vec<Figure>)], extra_html: &str) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>mfx report</title><style>\
         body{{font-family:sans-serif;max-width:1300px;margin:2em auto;color:#222}}\
         table{{border-collapse:collapse;margin:1em 0;font-size:13px}}td,th{{border:1px solid #ccc;padding:3px 7px;text-align:left}}\
         th{{background:#f3f3f3}}figure{{margin:1.5em 0}}img{{max-width:100%;border:1px solid #ddd}}figcaption{{color:#555;font-size:13px}}\
         .failed{{color:#b00}}.skipped{{color:#a60}}</style></head><body><h1>mfx report</h1>"
    );
    // Metadata: one line per distinct machine/run.
    h.push_str("<h2>Runs</h2><table id=\"runs\"><tr><th>run_id</th><th>suite</th><th>git_rev</th><th>adapter</th><th>backend</th><th>device type</th><th>driver</th><th>rows ok / skipped / failed</th></tr>");
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in &runs.rows {
        let k = (
            r.get("run_id").to_string(),
            r.get("adapter").to_string() + r.get("backend"),
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
                r.get("run_id") == run && format!("{}{}", r.get("adapter"), r.get("backend")) == *ad
            })
            .collect();
        let f = rs[0];
        let count = |s: &str| rs.iter().filter(|r| r.get("status") == s).count();
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} {}</td><td>{} / {} / {}</td></tr>",
            esc(run),
            esc(f.get("suite")),
            esc(f.get("git_rev")),
            esc(f.get("adapter")),
            esc(f.get("backend")),
            esc(f.get("device_type")),
            esc(f.get("driver")),
            esc(f.get("driver_info")),
            count("ok"),
            count("skipped"),
            count("failed")
        );
    }
    h.push_str("</table>");
    for (title, figs) in sections {
        let _ = write!(h, "<h2>{}</h2>", esc(title));
        for f in figs {
            // The page shows the SVG (vector, small enough to commit with reference runs); the
            // PNG beside it is for slides and is not tracked under results/reference/.
            let _ = write!(
                h,
                "<figure><img src=\"{0}.svg\" alt=\"{1}\"><figcaption>{1}. {2} (<a href=\"{0}.png\">PNG</a>)</figcaption></figure>",
                esc(&f.stem),
                esc(&f.title),
                esc(&f.caption)
            );
        }
    }
    h.push_str(extra_html);
    // Summary of ok rows.
    h.push_str("<h2>Rows</h2><table id=\"rows\"><tr><th>adapter (backend)</th><th>study</th><th>scene</th><th>resolution</th><th>method</th><th>axes</th><th>GPU ms (median)</th><th>× floor</th><th>speedup vs depth_peel</th><th>RMSE</th><th>max abs err</th><th>flag</th></tr>");
    for r in runs.rows.iter().filter(|r| r.ok()) {
        let _ = write!(
            h,
            "<tr><td>{} ({})</td><td>{}</td><td>{}</td><td>{}x{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(r.get("adapter")),
            esc(r.get("backend")),
            esc(r.get("study")),
            esc(r.get("scene_label")),
            r.get("width"),
            r.get("height"),
            esc(r.get("method")),
            esc(r.get("point_key").rsplit('|').next().unwrap_or("")),
            short(r.f("gpu_ms_median")),
            short(r.f("x_floor")),
            short(r.f("speedup_vs_depth_peel")),
            short(r.f("rmse")),
            short(r.f("max_abs_err")),
            esc(r.get("flag"))
        );
    }
    h.push_str("</table>");
    let bad: Vec<&Rec> = runs.rows.iter().filter(|r| !r.ok()).collect();
    let _ = write!(h, "<h2>Skipped and failed rows ({})</h2><table id=\"notok\"><tr><th>status</th><th>point</th><th>reason</th></tr>", bad.len());
    for r in bad {
        let _ = write!(
            h,
            "<tr class=\"{0}\"><td>{0}</td><td>{1}</td><td>{2}</td></tr>",
            esc(r.get("status")),
            esc(r.get("point_key")),
            esc(r.get("reason"))
        );
    }
    h.push_str("</table></body></html>\n");
    h
}

fn short(v: Option<f64>) -> String {
    match v {
        None => String::new(),
        Some(0.0) => "0".into(),
        Some(x) if x.is_infinite() => "inf".into(),
        Some(x) if x.abs() >= 100.0 => format!("{x:.0}"),
        Some(x) if x.abs() >= 0.01 => format!("{x:.3}"),
        Some(x) => format!("{x:.2e}"),
    }
}
