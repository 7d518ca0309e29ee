//! "Reproduction": the sources' published figures (`scenarios/papers/*.toml`) beside ours, read
//! from the rows the papers files point to. One table per source: figure, paper value, the
//! paper's ratio, ours (the measured ratio r = baseline / ours of the rule's column), and whether
//! it holds by the declared rule; a figure that cannot be reproduced says why. Empty when the run
//! holds no suite a papers file points to.

use std::fmt::Write;

use scenarios::papers::{self, Figure, PointRef};

use crate::cells::esc;
use crate::data::{Rec, Runs};

/// The row a point names: same suite, method, scene label, resolution and axis values; an ok row
/// first (a point measured twice, e.g. by two studies, reads the first ok one).
fn find<'a>(runs: &'a Runs, p: &PointRef) -> Option<&'a Rec> {
    let res = [p.resolution[0].to_string(), p.resolution[1].to_string()];
    let matches = |r: &&Rec| {
        r.get_name("suite") == p.suite
            && r.get_name("method") == p.method
            && r.get_name("scene_label") == p.scene
            && r.get_name("width") == res[0]
            && r.get_name("height") == res[1]
            && p.axes.iter().all(|(k, v)| same(r.get_name(k), v))
    };
    let mut hits = runs.rows.iter().filter(matches);
    let first = hits.clone().next();
    hits.find(|r| r.ok()).or(first)
}

/// A CSV cell equals a TOML value (numbers compared as numbers: "1" is 1.0).
fn same(cell: &str, v: &toml::Value) -> bool {
    match v {
        toml::Value::String(s) => cell == s,
        toml::Value::Boolean(b) => cell == b.to_string(),
        toml::Value::Integer(i) => cell.parse::<f64>().ok() == Some(*i as f64),
        toml::Value::Float(x) => cell.parse::<f64>().ok() == Some(*x),
        _ => false,
    }
}

fn num(x: f64) -> String {
    if x.is_infinite() {
        "∞".into()
    } else if x.abs() >= 100.0 {
        format!("{x:.0}")
    } else if x.abs() >= 0.1 {
        format!("{x:.2}")
    } else {
        format!("{x:.3}")
    }
}

/// What the two rows' GPU times are made of, measured (their slowest pass and its share of
/// the frame), for a figure ruled on a time: the reason a ratio holds or differs, from the run.
fn measured(f: &Figure, rows: Option<(&Rec, &Rec)>) -> String {
    let (Some(rule), Some((ro, rb))) = (&f.holds, rows) else {
        return String::new();
    };
    if !rule.column().ends_with("_ms_median") {
        return String::new();
    }
    let one = |r: &Rec| -> Option<String> {
        let (pass, ms, share) = crate::bounds::slowest_pass(r)?;
        Some(format!(
            "{}: {} {} of {} ms ({} %)",
            r.get_name("method"),
            pass,
            num(ms),
            num(r.f_name(rule.column())?),
            (100.0 * share).round()
        ))
    };
    match (one(ro), one(rb)) {
        (Some(a), Some(b)) => format!("ours {a}; baseline {b}"),
        _ => String::new(),
    }
}

/// The measured passes, then the figure's declared `why_differs` where the verdict is "differs"
/// or "within noise" (a figure that holds needs no excuse).
fn measured_and_why(f: &Figure, rows: Option<(&Rec, &Rec)>, verdict: &str) -> String {
    let m = measured(f, rows);
    let differs = verdict.starts_with("differs") || verdict.starts_with("within noise");
    match (&f.why_differs, differs) {
        (Some(why), true) if m.is_empty() => format!("why: {why}"),
        (Some(why), true) => format!("{m}. Why: {why}"),
        _ => m,
    }
}

/// The rows of a figure's point and its baseline, where the run holds both.
fn rows_of<'a>(runs: &'a Runs, f: &Figure) -> Option<(&'a Rec, &'a Rec)> {
    Some((
        find(runs, f.ours.as_ref()?)?,
        find(runs, f.baseline.as_ref()?)?,
    ))
}

/// What the run says for one figure (`rows`: [`rows_of`]): (ours, verdict).
fn ours(f: &Figure, rows: Option<(&Rec, &Rec)>) -> (String, String) {
    if !f.reproducible {
        return (
            "—".into(),
            format!("not reproducible: {}", f.reason.as_deref().unwrap_or("")),
        );
    }
    let (Some(o), Some(_), Some(rule)) = (&f.ours, &f.baseline, &f.holds) else {
        return ("—".into(), "no point declared".into());
    };
    let Some((ro, rb)) = rows else {
        return ("—".into(), format!("not in this run (suite {})", o.suite));
    };
    for r in [ro, rb] {
        if !r.ok() {
            return (
                "—".into(),
                format!("{}: {}", r.get_name("status"), r.get_name("reason")),
            );
        }
    }
    let (Some(vo), Some(vb)) = (ro.f_name(rule.column()), rb.f_name(rule.baseline_column())) else {
        return ("—".into(), format!("no {} in the rows", rule.column()));
    };
    let r = vb / vo;
    let interval = ratio_interval(rule.column(), rule.baseline_column(), ro, rb);
    let verdict = match interval {
        Some((lo, hi)) => verdict_over(rule, lo, hi, f.ratio),
        None => match rule.holds(r, f.ratio) {
            Some(true) => "holds",
            Some(false) => "differs",
            None => "undecided",
        },
    };
    let ours = match interval {
        Some((lo, hi)) => format!("r = {} ({}–{})", num(r), num(lo), num(hi)),
        None => format!("r = {}", num(r)),
    };
    (ours, format!("{verdict} ({})", rule.describe(f.ratio)))
}

/// The 95 % interval of r = baseline ÷ ours where both columns are median GPU times with their
/// bootstrap intervals (the other columns have none): r's ends pair one row's low end with the
/// other's high end.
fn ratio_interval(col: &str, base_col: &str, ro: &Rec, rb: &Rec) -> Option<(f64, f64)> {
    if col != "gpu_ms_median" || base_col != "gpu_ms_median" {
        return None;
    }
    let (olo, ohi) = (ro.f_name("gpu_ms_ci_lo")?, ro.f_name("gpu_ms_ci_hi")?);
    let (blo, bhi) = (rb.f_name("gpu_ms_ci_lo")?, rb.f_name("gpu_ms_ci_hi")?);
    (olo > 0.0 && ohi >= olo && bhi >= blo).then(|| (blo / ohi, bhi / olo))
}

/// A rule's verdict over an interval of r: "holds" or "differs" only when the whole interval
/// does; one that straddles the rule's boundary is "within noise" (a ratio of 1.00 against
/// "r > 1" flipped between two H200 runs of the same build before this).
fn verdict_over(rule: &papers::Rule, lo: f64, hi: f64, paper: Option<f64>) -> &'static str {
    let outside_within = match (rule.rule, paper, rule.factor) {
        (papers::RuleKind::RatioWithin, Some(p), Some(f)) => Some(hi < p / f || lo > p * f),
        _ => None,
    };
    match (rule.holds(lo, paper), rule.holds(hi, paper), outside_within) {
        (Some(true), Some(true), _) => "holds",
        (_, _, Some(true)) => "differs",
        (Some(false), Some(false), None) => "differs",
        (None, _, _) | (_, None, _) => "undecided",
        _ => "within noise",
    }
}

/// One source's table: its heading, its papers file's name, and a row of cells per figure
/// (row, figure, setup, paper, paper ratio, ours, verdict, measured and why).
pub(crate) struct Table {
    pub(crate) heading: String,
    pub(crate) name: String,
    pub(crate) rows: Vec<[String; 8]>,
}

/// The columns of every table.
pub(crate) const HEADER: [&str; 8] = [
    "row",
    "figure",
    "setup",
    "paper",
    "paper ratio",
    "ours",
    "holds / differs",
    "measured: slowest pass (ours; baseline), and why ours differs",
];

/// The note under the heading.
pub(crate) const NOTE: &str = "r = baseline ÷ ours of the rule's column (for times, ours' speed-up); the rule is declared in scenarios/papers/*.toml.";

/// Every source's table, or none when no row of `runs` is from a suite a papers file points to.
pub(crate) fn tables(runs: &Runs) -> Vec<Table> {
    let files: Vec<(&str, papers::PapersFile)> = papers::BUILTIN
        .iter()
        .filter_map(|(n, t)| papers::parse(t).ok().map(|f| (*n, f)))
        .collect();
    let suites: Vec<&str> = files
        .iter()
        .flat_map(|(_, f)| f.figures.iter())
        .flat_map(|f| f.ours.iter().chain(f.baseline.iter()))
        .map(|p| p.suite.as_str())
        .collect();
    if !runs
        .rows
        .iter()
        .any(|r| suites.contains(&r.get_name("suite")))
    {
        return Vec::new();
    }
    files
        .iter()
        .map(|(name, f)| Table {
            heading: format!(
                "{} — {} ({})",
                f.source.title, f.source.authors, f.source.venue
            ),
            name: name.to_string(),
            rows: f.figures.iter().map(|fig| cells(runs, fig)).collect(),
        })
        .collect()
}

/// One figure's cells.
fn cells(runs: &Runs, fig: &Figure) -> [String; 8] {
    let paper = match (fig.value, &fig.against, &fig.claim) {
        (Some(v), Some(a), _) => format!("{} {} vs {}", num(v), fig.metric, a),
        (Some(v), None, _) => format!("{} {}", num(v), fig.metric),
        (None, _, Some(c)) => c.clone(),
        _ => fig.metric.clone(),
    };
    let s = &fig.setup;
    let setup = format!(
        "{}{}, {}{}{}",
        s.gpu,
        s.resolution
            .map(|r| format!(", {}×{}", r[0], r[1]))
            .unwrap_or_default(),
        s.scene,
        s.triangles
            .map(|t| format!(" ({t} triangles)"))
            .unwrap_or_default(),
        s.layers
            .as_ref()
            .map(|l| format!(", {l}"))
            .unwrap_or_default()
    );
    let rows = rows_of(runs, fig);
    let (o, verdict) = ours(fig, rows);
    let why = measured_and_why(fig, rows, &verdict);
    [
        fig.row.to_string(),
        format!("{} {} ({})", fig.table, fig.section, fig.id),
        setup,
        paper,
        fig.ratio.map(num).unwrap_or_else(|| "—".into()),
        o,
        verdict,
        why,
    ]
}

/// The section's HTML, or "" when no row of `runs` is from a suite a papers file points to.
pub fn section(runs: &Runs) -> String {
    let tables = tables(runs);
    if tables.is_empty() {
        return String::new();
    }
    let mut h = format!(
        "<h2 id=\"reproduction\">Reproduction: the sources' published figures beside ours</h2><p class=\"note\">{}</p>",
        esc(NOTE)
    );
    for t in &tables {
        let _ = write!(
            h,
            "<h3>{}</h3><table class=\"repro\" id=\"repro-{}\"><tr>",
            esc(&t.heading),
            esc(&t.name)
        );
        for c in HEADER {
            let _ = write!(h, "<th>{}</th>", esc(c));
        }
        h.push_str("</tr>");
        for r in &t.rows {
            h.push_str("<tr>");
            for c in r {
                let _ = write!(h, "<td>{}</td>", esc(c));
            }
            h.push_str("</tr>");
        }
        h.push_str("</table>");
    }
    h
}

/// The same tables as markdown (`reproduction.md` beside the report, for a RUN.md), or "".
pub fn markdown(runs: &Runs) -> String {
    let tables = tables(runs);
    if tables.is_empty() {
        return String::new();
    }
    let cell = |c: &str| c.replace('|', "\\|").replace('\n', " ");
    let mut m = format!("### Reproduction: the sources' published figures beside ours\n\n{NOTE}\n");
    for t in &tables {
        let _ = write!(m, "\n#### {}\n\n| {} |\n|", t.heading, HEADER.join(" | "));
        m.push_str(&"---|".repeat(HEADER.len()));
        m.push('\n');
        for r in &t.rows {
            let row: Vec<String> = r.iter().map(|c| cell(c)).collect();
            let _ = writeln!(m, "| {} |", row.join(" | "));
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use schema::Status;

    const D: &str = "obj(path=models/dragon_vrip.ply.gz)";

    fn rec(method: &str, axes: &[(&str, &str)], ms: &str, status: Status) -> Rec {
        let mut m = std::collections::BTreeMap::new();
        for (k, v) in [
            ("suite", "seeds-buckets"),
            ("method", method),
            ("scene_label", D),
            ("width", "512"),
            ("height", "512"),
            ("status", status.name()),
            ("gpu_ms_median", ms),
            (
                "reason",
                if status == Status::Ok {
                    ""
                } else {
                    "scene: model file 'models/dragon_vrip.ply.gz' not found: fetch it with `bash scripts/fetch-dragon.sh`"
                },
            ),
        ] {
            m.insert(k.to_string(), v.to_string());
        }
        for (k, v) in axes {
            m.insert(k.to_string(), v.to_string());
        }
        Rec(m)
    }

    fn runs(rows: Vec<Rec>) -> Runs {
        Runs {
            header: Vec::new(),
            rows,
            sources: Vec::new(),
        }
    }

    #[test]
    fn each_figure_gets_ours_the_ratio_and_the_verdict_of_its_rule() {
        let r = runs(vec![
            rec("depth_peel", &[("max_layers", "256")], "40.0", Status::Ok),
            // 40 / 5 = 8: within 2× of 10.7 (holds).
            rec(
                "bdp",
                &[("bucket_count", "16"), ("bucket_pairing", "paired")],
                "5.0",
                Status::Ok,
            ),
            // 40 / 20 = 2: not within 2× of 5.3 (differs).
            rec("bdp2", &[("bucket_count", "32")], "20.0", Status::Ok),
        ]);
        let h = section(&r);
        let row = |id: &str| {
            let i = h
                .find(&format!("({id})"))
                .unwrap_or_else(|| panic!("{id} in {h}"));
            h[i..].split("</tr>").next().unwrap().to_string()
        };
        assert!(
            row("fig1.2-bdp").contains("r = 8.00") && row("fig1.2-bdp").contains("holds"),
            "{}",
            row("fig1.2-bdp")
        );
        assert!(row("fig1.2-bdp2").contains("r = 2.00") && row("fig1.2-bdp2").contains("differs"));
        // bdp over bdp2: 20 / 5 = 4 > 1.
        assert!(
            row("fig1.2-bdp-over-bdp2").contains("r = 4.00")
                && row("fig1.2-bdp-over-bdp2").contains("holds")
        );
        assert!(row("fig1.2-adp").contains("not in this run"));
        assert!(row("fig1.4-adp-fresnel").contains("not reproducible: An image only"));
        // Without pass times there is nothing measured to say; with them, each side's slowest pass.
        assert!(
            !row("fig1.2-bdp2").contains("slowest"),
            "{}",
            row("fig1.2-bdp2")
        );
        let mut timed = r.clone();
        for x in &mut timed.rows {
            let passes = match x.get_name("method") {
                "depth_peel" => r#"{"peel": 36.0, "composite": 4.0}"#,
                _ => r#"{"route": 18.0, "resolve": 2.0}"#,
            };
            x.0.insert("pass_ms".into(), passes.into());
        }
        let h = section(&timed);
        let i = h.find("(fig1.2-bdp2)").unwrap();
        let row = h[i..].split("</tr>").next().unwrap();
        assert!(
            row.contains("ours bdp2: route 18.00 of 20.00 ms (90 %); baseline depth_peel: peel 36.00 of 40.00 ms (90 %)"),
            "{row}"
        );
        // Every source has its table, every figure its row.
        for (name, text) in papers::BUILTIN {
            assert!(h.contains(&format!("id=\"repro-{name}\"")), "{name}");
            for fig in papers::parse(text).unwrap().figures {
                assert!(h.contains(&format!("({})", fig.id)), "{}", fig.id);
            }
        }
    }

    #[test]
    fn a_ratio_whose_interval_straddles_the_rule_is_within_noise_not_a_verdict() {
        // fig1.2-bdp-over-bdp2 rules r > 1 on bdp2 ÷ bdp. Medians 10.0 vs 9.9 (r = 1.01) whose
        // intervals overlap: within noise; 10.0 vs 8.0 with tight intervals: holds.
        let with_ci = |method: &str, axes: &[(&str, &str)], ms: &str, lo: &str, hi: &str| {
            let mut r = rec(method, axes, ms, Status::Ok);
            r.0.insert("gpu_ms_ci_lo".into(), lo.into());
            r.0.insert("gpu_ms_ci_hi".into(), hi.into());
            r
        };
        let bdp = [("bucket_count", "16"), ("bucket_pairing", "paired")];
        let bdp2 = [("bucket_count", "32")];
        let row_of = |h: &str| {
            let at = h.find("(fig1.2-bdp-over-bdp2)").unwrap();
            h[at..at + h[at..].find("</tr>").unwrap()].to_string()
        };
        let close = section(&runs(vec![
            with_ci("bdp", &bdp, "9.9", "9.7", "10.1"),
            with_ci("bdp2", &bdp2, "10.0", "9.8", "10.2"),
        ]));
        let row = row_of(&close);
        assert!(row.contains("within noise (r &gt; 1)"), "{row}");
        assert!(row.contains("r = 1.01 (0.97–1.05)"), "{row}");
        let apart = section(&runs(vec![
            with_ci("bdp", &bdp, "8.0", "7.9", "8.1"),
            with_ci("bdp2", &bdp2, "10.0", "9.9", "10.1"),
        ]));
        assert!(
            row_of(&apart).contains("holds (r &gt; 1)"),
            "{}",
            row_of(&apart)
        );
    }

    #[test]
    fn a_figure_that_differs_shows_why_and_one_that_holds_does_not() {
        // fig1.2-bdp declares why_differs: r = 40 / 20 = 2 is not within 2× of 10.7 (differs),
        // r = 40 / 5 = 8 is (holds).
        let row = |bdp_ms: &str| {
            let h = section(&runs(vec![
                rec("depth_peel", &[("max_layers", "256")], "40.0", Status::Ok),
                rec(
                    "bdp",
                    &[("bucket_count", "16"), ("bucket_pairing", "paired")],
                    bdp_ms,
                    Status::Ok,
                ),
            ]));
            let at = h.find("(fig1.2-bdp)").unwrap();
            h[at..at + h[at..].find("</tr>").unwrap()].to_string()
        };
        assert!(
            row("20.0").contains("differs") && row("20.0").contains("why: "),
            "{}",
            row("20.0")
        );
        assert!(
            row("5.0").contains("holds") && !row("5.0").contains("why"),
            "{}",
            row("5.0")
        );
    }

    #[test]
    fn the_markdown_has_the_html_tables_rows() {
        let r = runs(vec![
            rec("depth_peel", &[("max_layers", "256")], "40.0", Status::Ok),
            rec("bdp2", &[("bucket_count", "32")], "20.0", Status::Ok),
        ]);
        let (h, m) = (section(&r), markdown(&r));
        let rows = |text: &str, start: &str| text.matches(start).count();
        assert_eq!(
            rows(&h, "<tr><td>"),
            rows(&m, "\n| ") - 5,
            "one markdown row per figure (plus 5 header rows)"
        );
        assert!(
            m.contains("| r = 2.00 | differs (r within 2× of 5.3) |"),
            "{m}"
        );
        assert_eq!(markdown(&runs(vec![])), "");
    }

    #[test]
    fn a_skipped_point_shows_its_reason_and_a_run_of_other_suites_has_no_section() {
        let r = runs(vec![
            rec("depth_peel", &[("max_layers", "256")], "", Status::Skipped),
            rec(
                "bdp",
                &[("bucket_count", "16"), ("bucket_pairing", "paired")],
                "",
                Status::Skipped,
            ),
        ]);
        assert!(
            section(&r).contains("skipped: scene: model file"),
            "fetch reason shown"
        );
        let mut other = rec("bdp", &[], "1.0", Status::Ok);
        other.0.insert("suite".into(), "buckets".into());
        assert_eq!(section(&runs(vec![other])), "");
    }
}
