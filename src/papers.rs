//! Checks the papers files (`scenarios/papers/*.toml`) against the suites, before any GPU work:
//! each point's suite exists, has a study running its method at its resolution on its scene,
//! sweeps each named axis with the named value, and the named axes pick exactly one point (a
//! figure whose points match two rows is ambiguous); each reproducible figure has its faithful
//! points or says what it `needs`, a rule that can fail (one that accepts r = 1 holds on rows
//! with no effect) on declared columns, and `why_differs` states numbers only through facts
//! read from its rows; each unreproducible one says why. Every problem at once.

use std::collections::BTreeSet;

use scenarios::papers::{self, Figure, PapersFile, PointRef, Rule, RuleKind};
use scenarios::{ParamValue, Problem, Suite};

use bench_core::study::{by_kind, Methods};

use crate::STUDIES;

/// Every problem of the built-in papers files (empty when all hold together).
pub fn check_builtin() -> Vec<Problem> {
    papers::BUILTIN
        .iter()
        .flat_map(|(name, text)| check_text(text, &format!("scenarios/papers/{name}.toml")))
        .collect()
}

/// Every problem of one papers file's text.
pub fn check_text(text: &str, file: &str) -> Vec<Problem> {
    match papers::parse(text) {
        Ok(f) => check_file(&f, file),
        Err(e) => vec![Problem::new(file, "top level", "", e.to_string())],
    }
}

/// Every problem of a parsed papers file.
pub fn check_file(f: &PapersFile, file: &str) -> Vec<Problem> {
    let mut out = Vec::new();
    let mut ids = BTreeSet::new();
    for (i, fig) in f.figures.iter().enumerate() {
        let table = format!("figure {i} ({})", fig.id);
        let mut p = |key: &str, msg: String| out.push(Problem::new(file, &table, key, msg));
        if !ids.insert(fig.id.clone()) {
            p("id", "duplicate figure id".into());
        }
        if !(1..=20).contains(&fig.row) {
            p("row", "must be a row 1–20 of figures.md A.1".into());
        }
        check_figure(fig, &mut p);
    }
    out
}

fn check_figure(fig: &Figure, p: &mut impl FnMut(&str, String)) {
    if !fig.reproducible {
        if fig.reason.as_deref().is_none_or(|r| r.trim().is_empty()) {
            p("reason", "reproducible = false needs the reason".into());
        }
        if fig.why_differs.is_some() {
            p(
                "why_differs",
                "a figure that is not reproduced cannot differ: its reason says why".into(),
            );
        }
        for (key, set) in [
            ("ours", fig.ours.is_some()),
            ("baseline", fig.baseline.is_some()),
            ("order", fig.order.is_some()),
            ("holds", fig.holds.is_some()),
            ("needs", fig.needs.is_some()),
            ("variant", !fig.variants.is_empty()),
        ] {
            if set {
                p(
                    key,
                    "a figure that is not reproduced has no points, rule or variants".into(),
                );
            }
        }
        return;
    }
    let Some(rule) = &fig.holds else {
        p(
            "holds",
            "a reproducible figure needs its rule (or reproducible = false with the reason)".into(),
        );
        return;
    };
    let faithful = !fig.points().is_empty();
    match (&fig.needs, faithful) {
        (Some(_), true) => p(
            "needs",
            "the faithful points are declared: the figure no longer needs a variant built".into(),
        ),
        (None, false) => p(
            "",
            "a reproducible figure needs its faithful points (ours and baseline, or order), or `needs` saying what is not built"
                .into(),
        ),
        (Some(n), false) => {
            if n.why.trim().is_empty() || n.variant.trim().is_empty() {
                p(
                    "needs",
                    "say which variant is needed and why today's is not it".into(),
                );
            }
            if let Some(bad) = n.items.iter().find(|i| !(1..=11).contains(*i)) {
                p(
                    "needs.items",
                    format!("{bad}: issue 45 lists items 1–11"),
                );
            }
        }
        (None, true) => {}
    }
    check_rule(rule, fig.ratio, "holds", p);
    if faithful {
        check_points(
            rule,
            fig.ours.as_ref(),
            fig.baseline.as_ref(),
            fig.order.as_deref(),
            "",
            p,
        );
    }
    let mut names = BTreeSet::new();
    for v in &fig.variants {
        let at = format!("variant.{}", v.name);
        if !names.insert(v.name.clone()) || v.name.contains(':') || v.name.is_empty() {
            p(&at, "a variant needs a unique name without ':'".into());
        }
        let vrule = v.holds.as_ref().unwrap_or(rule);
        if let Some(r) = &v.holds {
            check_rule(r, fig.ratio, &format!("{at}.holds"), p);
        }
        if v.points().is_empty() {
            p(
                &at,
                "a variant needs its points (ours and baseline, or order)".into(),
            );
        }
        check_points(
            vrule,
            v.ours.as_ref(),
            v.baseline.as_ref(),
            v.order.as_deref(),
            &format!("{at}."),
            p,
        );
    }
    check_facts(fig, p);
}

fn check_rule(rule: &Rule, paper: Option<f64>, key: &str, p: &mut impl FnMut(&str, String)) {
    for why in rule.problems(paper) {
        p(key, why);
    }
    let cols = [
        (format!("{key}.column"), rule.column()),
        (format!("{key}.baseline_column"), rule.baseline_column()),
    ];
    for (k, col) in cols {
        if schema::by_name(col).is_none() {
            p(&k, format!("'{col}' is not a declared runs.csv column"));
        }
    }
}

fn check_points(
    rule: &Rule,
    ours: Option<&PointRef>,
    baseline: Option<&PointRef>,
    order: Option<&[PointRef]>,
    prefix: &str,
    p: &mut impl FnMut(&str, String),
) {
    match (rule.rule, order) {
        (RuleKind::Order, Some(o)) if o.len() >= 2 && ours.is_none() && baseline.is_none() => {}
        (RuleKind::Order, _) => p(
            &format!("{prefix}order"),
            "rule = order needs `order` with two points or more (and no ours or baseline)".into(),
        ),
        (_, Some(_)) => p(
            &format!("{prefix}order"),
            "`order` needs rule = order".into(),
        ),
        (_, None) if ours.is_none() || baseline.is_none() => p(
            prefix.trim_end_matches('.'),
            "needs ours and baseline".into(),
        ),
        _ => {}
    }
    let named = [("ours", ours), ("baseline", baseline)]
        .into_iter()
        .filter_map(|(k, pt)| pt.map(|pt| (k.to_string(), pt)))
        .chain(
            order
                .unwrap_or(&[])
                .iter()
                .enumerate()
                .map(|(i, pt)| (format!("order[{i}]"), pt)),
        );
    for (key, point) in named {
        if let Err(why) = check_point(point) {
            p(&format!("{prefix}{key}"), why.to_string());
        }
    }
}

/// Facts name rows of the figure and declared columns; `why_differs` uses each and states no
/// number that is not a fact or one of the figure's published numbers.
fn check_facts(fig: &Figure, p: &mut impl FnMut(&str, String)) {
    if let Some(w) = &fig.why_differs {
        if w.trim().is_empty() {
            p("why_differs", "empty: say why, or leave the key out".into());
        }
    }
    let rows: Vec<String> = fig.named_points().into_iter().map(|(n, _)| n).collect();
    let used: BTreeSet<&str> = fig.placeholders().into_iter().collect();
    for name in &used {
        if !fig.facts.contains_key(*name) {
            p(
                "why_differs",
                format!("{{{name}}} is not a fact of the figure (facts.{name})"),
            );
        }
    }
    for (name, fact) in &fig.facts {
        let key = format!("facts.{name}");
        let over_used = fig.facts.values().any(|f| f.over.as_deref() == Some(name));
        if !used.contains(name.as_str()) && !over_used {
            p(&key, "not used by why_differs or another fact".into());
        }
        if !rows.contains(&fact.row) {
            p(
                &key,
                format!("row '{}' is not one of {}", fact.row, rows.join(", ")),
            );
        }
        if fact.column.is_some() == fact.pass.is_some() {
            p(&key, "name one of column or pass".into());
        }
        for col in fact.column.iter().chain(fact.per.iter()) {
            if schema::by_name(col).is_none() {
                p(&key, format!("'{col}' is not a declared runs.csv column"));
            }
        }
        if let Some(o) = &fact.over {
            if o == name || !fig.facts.contains_key(o) {
                p(
                    &key,
                    format!("over = '{o}' is not another fact of the figure"),
                );
            }
        }
    }
    let published = published_numbers(fig);
    for (key, text) in [
        ("why_differs", fig.why_differs.as_deref()),
        ("needs.why", fig.needs.as_ref().map(|n| n.why.as_str())),
    ] {
        for n in papers::bare_numbers(text.unwrap_or("")) {
            if !published.contains(&n) {
                p(
                    key,
                    format!("states {n} outside a {{fact}}: a measured number comes from the rows"),
                );
            }
        }
    }
}

/// The numbers of the figure's published fields, where a number `why_differs` quotes may come
/// from (every numeral, glued to a word or not: "16" of "16 bucket pairs", "32" of "RGBA32F").
fn published_numbers(fig: &Figure) -> BTreeSet<String> {
    let text = published_text(fig);
    let mut out = BTreeSet::new();
    let mut cur = String::new();
    for c in text.chars().chain(std::iter::once(' ')) {
        if c.is_ascii_digit() || (!cur.is_empty() && (c == '.' || c == ',')) {
            cur.push(c);
        } else if !cur.is_empty() {
            out.insert(cur.trim_end_matches(['.', ',']).to_string());
            cur.clear();
        }
    }
    out
}

/// The figure's published fields.
fn published_text(fig: &Figure) -> String {
    let s = &fig.setup;
    [
        fig.value.map(|v| format!("{v}")),
        fig.ratio.map(|v| format!("{v}")),
        fig.against.clone(),
        fig.claim.clone(),
        Some(fig.table.clone()),
        Some(fig.section.clone()),
        Some(s.gpu.clone()),
        Some(s.scene.clone()),
        s.layers.clone(),
        s.triangles.map(|t| t.to_string()),
    ]
    .into_iter()
    .flatten()
    .collect::<Vec<_>>()
    .join(" | ")
}

/// A TOML value equals a point's value (numbers as numbers: 1 is 1.0).
fn same(v: &ParamValue, t: &toml::Value) -> bool {
    match (v, ParamValue::from_toml(t)) {
        (ParamValue::Int(a), Some(ParamValue::Float(b))) => *a as f64 == b,
        (ParamValue::Float(a), Some(ParamValue::Int(b))) => *a == b as f64,
        (a, Some(b)) => *a == b,
        (_, None) => false,
    }
}

/// Whether exactly one point of the point's suite is the one it names: some study runs its
/// method at its resolution on its scene and sweeps each named axis with the named value, and
/// the named axes tell it from every other point there (defaults resolved).
fn check_point(pt: &PointRef) -> Result<(), PointMismatch> {
    let suite = Suite::load(&pt.suite).map_err(|error| PointMismatch::Suite {
        suite: pt.suite.clone(),
        error,
    })?;
    let mut why = PointMismatch::NoStudy {
        suite: pt.suite.clone(),
        method: pt.method.clone(),
    };
    let mut matches = BTreeSet::new();
    for spec in &suite.studies {
        let Some(study) = by_kind(STUDIES, spec.kind) else {
            continue;
        };
        let runs_method = match study.methods() {
            Methods::List(_) => spec.methods.iter().any(|m| m == &pt.method),
            Methods::Implicit(m) => m == pt.method,
        };
        if !runs_method {
            continue;
        }
        let res = (pt.resolution[0], pt.resolution[1]);
        if !suite.study_resolutions(spec, false).contains(&res) {
            why = PointMismatch::Resolution {
                study: spec.index,
                suite: pt.suite.clone(),
                width: res.0,
                height: res.1,
            };
            continue;
        }
        let labels: Vec<String> = spec.scenes.iter().map(|s| s.label()).collect();
        if !labels.contains(&pt.scene) {
            why = PointMismatch::Scene {
                study: spec.index,
                suite: pt.suite.clone(),
                scene: pt.scene.clone(),
                labels,
            };
            continue;
        }
        if let Some(b) = swept(spec, study, pt, &suite) {
            why = PointMismatch::Axes(b);
            continue;
        }
        let Ok(points) = bench_core::study::points(study, spec) else {
            why = PointMismatch::Unresolved {
                study: spec.index,
                suite: pt.suite.clone(),
            };
            continue;
        };
        for ps in points.iter().filter(|ps| ps.method == pt.method) {
            let fits = pt
                .axes
                .iter()
                .all(|(k, v)| ps.point.get(k).is_some_and(|pv| same(pv, v)));
            if fits {
                matches.insert(ps.point.values().label());
            }
        }
    }
    match matches.len() {
        0 => Err(why),
        1 => Ok(()),
        n => Err(PointMismatch::Ambiguous {
            n,
            suite: pt.suite.clone(),
            points: matches.into_iter().collect(),
        }),
    }
}

/// Why a figure's point is not exactly one point of its suite (the last study's reason where
/// none runs it).
#[derive(Debug, thiserror::Error)]
enum PointMismatch {
    #[error("suite '{suite}': {error}")]
    Suite {
        suite: String,
        error: scenarios::SceneError,
    },
    #[error("no study of suite '{suite}' runs method '{method}'")]
    NoStudy { suite: String, method: String },
    #[error("study {study} of '{suite}' does not run {width}x{height}")]
    Resolution {
        study: usize,
        suite: String,
        width: u32,
        height: u32,
    },
    #[error("study {study} of '{suite}' has no scene '{scene}' (it has: {})", .labels.join(", "))]
    Scene {
        study: usize,
        suite: String,
        scene: String,
        labels: Vec<String>,
    },
    /// A named axis the study does not declare or sweep with the named value ([`swept`]).
    #[error("{0}")]
    Axes(String),
    #[error("study {study} of '{suite}' does not resolve")]
    Unresolved { study: usize, suite: String },
    #[error("matches {n} points of '{suite}' ({}): name the axis that tells them apart", .points.join("; "))]
    Ambiguous {
        n: usize,
        suite: String,
        points: Vec<String>,
    },
}

/// Why a study table cannot run the named axis values (None: each is declared and swept).
fn swept(
    spec: &scenarios::StudySpec,
    study: &dyn bench_core::study::Study,
    pt: &PointRef,
    suite: &Suite,
) -> Option<String> {
    let declared = study.axes(&pt.method);
    for (k, v) in &pt.axes {
        // An axis the method does not read leaves its cell empty: no row would match.
        let Some(axis) = declared.iter().find(|a| a.name() == k) else {
            return Some(format!("method '{}' does not read axis '{k}'", pt.method));
        };
        let Some(v) = ParamValue::from_toml(v) else {
            return Some(format!("axis '{k}': {v} is not a scalar"));
        };
        let values = spec
            .method_axes
            .get(&pt.method)
            .and_then(|o| o.get(k))
            .or_else(|| spec.axes.get(k));
        match values {
            // Not swept: the axis's default is the one value the table runs.
            None if axis
                .kind
                .default_value()
                .is_some_and(|d| same(&d, &to_toml(&v))) => {}
            None => {
                return Some(format!(
                    "study {} of '{}' does not sweep axis '{k}'",
                    spec.index, suite.name
                ))
            }
            Some(vals) if !vals.iter().any(|x| same(x, &to_toml(&v))) => {
                return Some(format!(
                    "study {} of '{}' sweeps '{k}' over {} but not {v}",
                    spec.index,
                    suite.name,
                    vals.iter()
                        .map(|x| x.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            }
            _ => {}
        }
    }
    None
}

fn to_toml(v: &ParamValue) -> toml::Value {
    match v {
        ParamValue::Bool(b) => toml::Value::Boolean(*b),
        ParamValue::Int(i) => toml::Value::Integer(*i),
        ParamValue::Float(x) => toml::Value::Float(*x),
        ParamValue::Str(s) => toml::Value::String(s.clone()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_builtin_papers_files_check_against_the_suites() {
        let p = check_builtin();
        assert!(p.is_empty(), "{}", scenarios::problem::report(&p));
    }

    fn first_figure_with(text: &str, from: &str, to: &str) -> Vec<Problem> {
        assert!(text.contains(from), "the fixture has {from}");
        check_text(&text.replacen(from, to, 1), "t.toml")
    }

    fn liu() -> &'static str {
        papers::BUILTIN[0].1
    }

    #[test]
    fn an_unknown_key_suite_method_axis_or_value_is_refused() {
        let text = liu();
        let all = |p: &[Problem]| scenarios::problem::report(p);
        let p = first_figure_with(
            text,
            "what = \"mfx's depth-range",
            "colour = 1\nwhat = \"mfx's depth-range",
        );
        assert!(all(&p).contains("unknown field `colour`"), "{}", all(&p));
        let p = first_figure_with(
            text,
            "suite = \"seeds-buckets\"",
            "suite = \"seeds-bucket\"",
        );
        assert!(all(&p).contains("seeds-bucket"), "{}", all(&p));
        let p = first_figure_with(text, "method = \"bdp\"", "method = \"bdq\"");
        assert!(all(&p).contains("runs method 'bdq'"), "{}", all(&p));
        let p = first_figure_with(text, "bucket_count = 16", "bucket_count = 12");
        assert!(all(&p).contains("but not 12"), "{}", all(&p));
        let p = first_figure_with(text, "bucket_count = 16", "bucket_cnt = 16");
        assert!(
            all(&p).contains("does not read axis 'bucket_cnt'"),
            "{}",
            all(&p)
        );
        let p = first_figure_with(
            text,
            "resolution = [512, 512], axes = { bucket_count = 16",
            "resolution = [64, 64], axes = { bucket_count = 16",
        );
        assert!(all(&p).contains("does not run 64x64"), "{}", all(&p));
        let p = first_figure_with(text, "reproducible = true", "reproducible = false");
        assert!(all(&p).contains("needs the reason"), "{}", all(&p));
        // An empty reason (the old text left behind as a comment line).
        let p = first_figure_with(text, "why_differs = \"", "why_differs = \" \"\n# \"");
        assert!(all(&p).contains("empty: say why"), "{}", all(&p));
    }

    #[test]
    fn a_figure_whose_points_match_two_rows_is_refused() {
        // Without `effect`, depth peeling's point matches its transparency and translucency
        // rows (fig1.2's baseline before issue 45).
        let p = first_figure_with(
            liu(),
            "axes = { max_layers = 256, effect = \"transparency\" } }",
            "axes = { max_layers = 256 } }",
        );
        let all = scenarios::problem::report(&p);
        assert!(
            all.contains("matches 2 points") && all.contains("effect=translucency"),
            "{all}"
        );
    }

    #[test]
    fn a_rule_that_holds_on_no_effect_is_refused() {
        let p = first_figure_with(
            papers::BUILTIN[1].1,
            "holds = { rule = \"ratio_within\", factor = 2.0 }",
            "holds = { rule = \"ratio_within\", factor = 4.0 }",
        );
        let all = scenarios::problem::report(&p);
        assert!(all.contains("cannot fail"), "{all}");
    }

    #[test]
    fn a_figure_says_what_it_needs_or_names_its_faithful_points() {
        let text = liu();
        let all = |p: &[Problem]| scenarios::problem::report(p);
        // fig1.2-bdp without its faithful points (the first `ours` and `baseline` lines of the
        // file) and without `needs` has nothing to rule.
        let mut no_points = text.to_string();
        for key in ["\nours = ", "\nbaseline = "] {
            let start = no_points.find(key).unwrap() + 1;
            let end = start + no_points[start..].find('\n').unwrap();
            no_points.replace_range(start..=end, "");
        }
        let p = check_text(&no_points, "t.toml");
        assert!(all(&p).contains("needs its faithful points"), "{}", all(&p));
        // A needs beside faithful points is stale.
        let p = first_figure_with(
            text,
            "holds = { rule = \"ratio_within\", factor = 2.0 }\n\n[[figure]]\nid = \"fig1.3-kbuffer-side-views\"",
            "holds = { rule = \"ratio_within\", factor = 2.0 }\nneeds = { variant = \"x\", why = \"y\" }\n\n[[figure]]\nid = \"fig1.3-kbuffer-side-views\"",
        );
        assert!(all(&p).contains("no longer needs"), "{}", all(&p));
    }

    #[test]
    fn why_differs_states_numbers_only_through_facts() {
        let text = liu();
        let all = |p: &[Problem]| scenarios::problem::report(p);
        // The statement issue 45 found: "16 passes at about 1 ms" where the rows say otherwise.
        let p = first_figure_with(
            text,
            "({dp_pass_ms} ms; depth peeling ran {dp_passes})",
            "(about 1 ms; depth peeling ran 16)",
        );
        assert!(all(&p).contains("states 1 outside a {fact}"), "{}", all(&p));
        let p = first_figure_with(text, "{dp_pass_ms}", "{dp_pas_ms}");
        assert!(all(&p).contains("{dp_pas_ms} is not a fact"), "{}", all(&p));
        let p = first_figure_with(
            text,
            "row = \"full-mesh-range:baseline\", column = \"geometry_passes\"",
            "row = \"full-mesh:baseline\", column = \"geometry_pases\"",
        );
        assert!(
            all(&p).contains("row 'full-mesh:baseline' is not one of")
                && all(&p).contains("'geometry_pases' is not a declared"),
            "{}",
            all(&p)
        );
    }
}
