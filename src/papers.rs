//! Checks the papers files (`scenarios/papers/*.toml`) against the suites, before any GPU work:
//! each point's suite exists, has a study running its method at its resolution on its scene, and
//! sweeps each named axis with the named value; each reproducible figure has its points and a
//! decidable rule on a declared column; each unreproducible one says why. Every problem at once.

use std::collections::BTreeSet;

use scenarios::papers::{self, PapersFile, PointRef};
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
        Err(e) => vec![Problem::new(file, "top level", "", e)],
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
            continue;
        }
        if fig
            .why_differs
            .as_deref()
            .is_some_and(|w| w.trim().is_empty())
        {
            p("why_differs", "empty: say why, or leave the key out".into());
        }
        let (Some(ours), Some(base), Some(rule)) = (&fig.ours, &fig.baseline, &fig.holds) else {
            p(
                "",
                "a reproducible figure needs ours, baseline and holds (or reproducible = false with the reason)".into(),
            );
            continue;
        };
        for why in rule.problems(fig.ratio) {
            p("holds", why);
        }
        for (key, col) in [
            ("holds.column", rule.column()),
            ("holds.baseline_column", rule.baseline_column()),
        ] {
            if schema::by_name(col).is_none() {
                p(key, format!("'{col}' is not a declared runs.csv column"));
            }
        }
        for (key, point) in [("ours", ours), ("baseline", base)] {
            if let Err(why) = check_point(point) {
                out.push(Problem::new(file, &table, key, why));
            }
        }
    }
    out
}

/// Whether some study of the point's suite runs exactly this point.
fn check_point(pt: &PointRef) -> Result<(), String> {
    let suite = Suite::load(&pt.suite).map_err(|e| format!("suite '{}': {e}", pt.suite))?;
    let mut why = format!(
        "no study of suite '{}' runs method '{}'",
        pt.suite, pt.method
    );
    for spec in &suite.studies {
        let Some(study) = by_kind(STUDIES, &spec.kind) else {
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
            why = format!(
                "study {} of '{}' does not run {}x{}",
                spec.index, pt.suite, res.0, res.1
            );
            continue;
        }
        let labels: Vec<String> = spec.scenes.iter().map(|s| s.label()).collect();
        if !labels.contains(&pt.scene) {
            why = format!(
                "study {} of '{}' has no scene '{}' (it has: {})",
                spec.index,
                pt.suite,
                pt.scene,
                labels.join(", ")
            );
            continue;
        }
        let mut bad = None;
        let declared = study.axes(&pt.method);
        for (k, v) in &pt.axes {
            // An axis the method does not read leaves its cell empty: no row would match.
            if !declared.iter().any(|a| a.name() == k) {
                bad = Some(format!("method '{}' does not read axis '{k}'", pt.method));
                break;
            }
            let Some(v) = ParamValue::from_toml(v) else {
                bad = Some(format!("axis '{k}': {v} is not a scalar"));
                break;
            };
            let values = spec
                .method_axes
                .get(&pt.method)
                .and_then(|o| o.get(k))
                .or_else(|| spec.axes.get(k));
            match values {
                None => {
                    bad = Some(format!(
                        "study {} of '{}' does not sweep axis '{k}'",
                        spec.index, pt.suite
                    ))
                }
                Some(vals) if !vals.contains(&v) => {
                    bad = Some(format!(
                        "study {} of '{}' sweeps '{k}' over {} but not {v}",
                        spec.index,
                        pt.suite,
                        vals.iter()
                            .map(|x| x.to_string())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ))
                }
                _ => {}
            }
            if bad.is_some() {
                break;
            }
        }
        match bad {
            None => return Ok(()),
            Some(b) => why = b,
        }
    }
    Err(why)
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

    #[test]
    fn an_unknown_key_suite_method_axis_or_value_is_refused() {
        let text = papers::BUILTIN[0].1;
        let all = |p: &[Problem]| scenarios::problem::report(p);
        let p = first_figure_with(text, "[figure.ours]\n", "[figure.ours]\ncolour = 1\n");
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
            "resolution = [512, 512]\n[figure.ours.axes]",
            "resolution = [64, 64]\n[figure.ours.axes]",
        );
        assert!(all(&p).contains("does not run 64x64"), "{}", all(&p));
        let p = first_figure_with(text, "reproducible = true", "reproducible = false");
        assert!(all(&p).contains("needs the reason"), "{}", all(&p));
        // The first figure says why it differs: not on a figure that is not reproduced, and
        // never empty.
        let p = first_figure_with(
            text,
            "reproducible = true\nwhy_differs",
            "reproducible = false\nreason = \"x\"\nwhy_differs",
        );
        assert!(all(&p).contains("cannot differ"), "{}", all(&p));
        // An empty reason (the old text left behind as a comment line).
        let p = first_figure_with(text, "why_differs = \"", "why_differs = \" \"\n# \"");
        assert!(all(&p).contains("empty: say why"), "{}", all(&p));
    }
}
