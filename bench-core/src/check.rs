//! One validation pass over a suite before any GPU work: every problem at once, each naming the
//! file, the table, the key, the value and the alternatives. What it checks beyond the suite's
//! structure (`Suite::parse`): study kinds, study options, method lists, axes against the
//! methods that declare them (unknown axis, wrong type, out of range, cross-axis rules), scene
//! generators and their parameters, and the model files scenes read (missing, a directory,
//! unreadable, no usable triangle, malformed faces). What depends on the adapter (features,
//! limits, memory) is not a suite problem: it becomes a `skipped` row when the sweep runs.

use std::collections::BTreeSet;

use scenarios::suite::{study_table, STUDY_KEYS};
use scenarios::{ParamValue, Problem, SceneError, StudySpec, Suite};

use crate::axes::Axis;
use crate::study::{by_kind, points, Methods, PointSpec, Study};

/// Every problem of `suite` (empty when it can run).
pub fn check_suite(studies: &[&dyn Study], suite: &Suite) -> Vec<Problem> {
    let mut out = Vec::new();
    for (software, table) in [(false, "[timing]"), (true, "[software]")] {
        if software && suite.software.is_none() {
            continue;
        }
        if let Err(why) = crate::measure::TimingPlan::from_spec(&suite.timing_for(software)) {
            out.push(Problem::new(&suite.source, table, "", why.to_string()));
        }
    }
    for spec in &suite.studies {
        check_study(studies, suite, spec, &mut out);
    }
    out
}

/// Loads a suite and checks it: `Err` holds every problem (structure and meaning) of every
/// table.
pub fn load(studies: &[&dyn Study], name_or_path: &str) -> Result<Suite, Vec<Problem>> {
    let (text, source) = Suite::read(name_or_path)
        .map_err(|e| vec![Problem::new(name_or_path, "suite", "", e.to_string())])?;
    match check_text(studies, &text, &source) {
        (Some(suite), problems) if problems.is_empty() => Ok(suite),
        (_, problems) => Err(problems),
    }
}

/// Parses and checks a suite's text: every problem of every table at once. A structural problem
/// (`Suite::parse_partial`) leaves its value at the default, and the rest is still checked.
pub fn check_text(
    studies: &[&dyn Study],
    text: &str,
    source: &str,
) -> (Option<Suite>, Vec<Problem>) {
    let (suite, mut problems) = Suite::parse_partial(text, source);
    if let Some(suite) = &suite {
        // A timing table's own problems are already named by the parse: its plan's check would
        // only say the same again.
        let parsed = problems.clone();
        problems.extend(check_suite(studies, suite).into_iter().filter(|p| {
            !(p.key.is_empty()
                && ["[timing]", "[software]"].contains(&p.table.as_str())
                && parsed.iter().any(|q| q.table == p.table))
        }));
    }
    (suite, problems)
}

fn check_study(studies: &[&dyn Study], suite: &Suite, spec: &StudySpec, out: &mut Vec<Problem>) {
    let file = suite.source.as_str();
    let table = study_table(spec.index, spec.kind);
    let before = out.len();
    let Some(study) = by_kind(studies, spec.kind) else {
        out.push(
            Problem::new(
                file,
                &format!("study {}", spec.index),
                "kind",
                "no study of this kind in this binary",
            )
            .value(spec.kind)
            .known(studies.iter().map(|s| s.kind().name())),
        );
        return;
    };

    // The table's own options.
    let options = study.options();
    for (k, v) in &spec.extra {
        let known = || {
            STUDY_KEYS
                .iter()
                .copied()
                .chain(options.iter().map(|o| o.name))
                .collect::<Vec<_>>()
        };
        match options.iter().find(|o| o.name == k) {
            None => out.push(
                Problem::new(file, &table, k, "unknown key (axes go in `axes`)")
                    .value(v)
                    .known(known()),
            ),
            Some(o) => {
                let checked = ParamValue::from_toml(v)
                    .ok_or_else(|| scenarios::params::NotExpected {
                        expected: o.kind.expected(),
                    })
                    .and_then(|pv| o.kind.check(&pv));
                if let Err(why) = checked {
                    out.push(Problem::new(file, &table, k, why.to_string()).value(v));
                }
            }
        }
    }
    for why in study.check_table(spec) {
        out.push(Problem::new(file, &table, "", why));
    }

    // The methods list.
    let methods: Vec<String> = match study.methods() {
        Methods::List(known) => {
            if !spec.methods_given {
                out.push(
                    Problem::new(
                        file,
                        &table,
                        "methods",
                        "missing: this study needs methods = [...]",
                    )
                    .known(&known),
                );
            } else if spec.methods.is_empty() {
                out.push(
                    Problem::new(file, &table, "methods", "is empty: nothing would run")
                        .known(&known),
                );
            }
            for m in &spec.methods {
                if !known.contains(&m.as_str()) {
                    out.push(
                        Problem::new(file, &table, "methods", "unknown method")
                            .value(m)
                            .known(&known),
                    );
                }
            }
            spec.methods
                .iter()
                .filter(|m| known.contains(&m.as_str()))
                .cloned()
                .collect()
        }
        Methods::Implicit(m) => {
            if spec.methods_given {
                out.push(Problem::new(
                    file,
                    &table,
                    "methods",
                    format!(
                        "this study takes no methods list (every point runs '{m}'; sweep `axes`)"
                    ),
                ));
            }
            vec![m.to_string()]
        }
    };

    // Axes: each must be declared by some method of the study, and each value must suit every
    // method that declares it (a value only some of them accept belongs in method_axes).
    let declared: Vec<(String, Vec<Axis>)> =
        methods.iter().map(|m| (m.clone(), study.axes(m))).collect();
    let all_names: BTreeSet<&str> = declared
        .iter()
        .flat_map(|(_, a)| a.iter().map(|x| x.name()))
        .collect();
    let axes_table = format!("{table} › axes");
    for (k, values) in &spec.axes {
        let declaring: Vec<(&str, &Axis)> = declared
            .iter()
            .filter(|(m, _)| !spec.method_axes.get(m).is_some_and(|o| o.contains_key(k)))
            .filter_map(|(m, a)| a.iter().find(|x| x.name() == k).map(|x| (m.as_str(), x)))
            .collect();
        if !all_names.contains(k.as_str()) {
            out.push(
                Problem::new(
                    file,
                    &axes_table,
                    k,
                    "no method of this study declares this axis",
                )
                .known(&all_names),
            );
            continue;
        }
        for v in values {
            let refused: Vec<(&str, String)> = declaring
                .iter()
                .filter_map(|(m, a)| a.kind.check(v).err().map(|why| (*m, why.to_string())))
                .collect();
            if refused.is_empty() {
                continue;
            }
            if refused.len() == declaring.len() {
                let who: Vec<&str> = refused.iter().map(|(m, _)| *m).collect();
                out.push(
                    Problem::new(
                        file,
                        &axes_table,
                        k,
                        format!("{} (for {})", refused[0].1, who.join(", ")),
                    )
                    .value(v),
                );
            } else {
                for (m, why) in refused {
                    out.push(
                        Problem::new(file, &axes_table, k, format!("{why} (for {m}, which other methods here accept: give {m} its own values in method_axes.{m})"))
                            .value(v),
                    );
                }
            }
        }
    }
    for (m, over) in &spec.method_axes {
        let Some((_, axes)) = declared.iter().find(|(n, _)| n == m) else {
            continue;
        };
        let tn = format!("{table} › method_axes.{m}");
        for (k, values) in over {
            match axes.iter().find(|a| a.name() == k) {
                None => out.push(
                    Problem::new(file, &tn, k, format!("{m} does not declare this axis"))
                        .known(axes.iter().map(|a| a.name())),
                ),
                Some(a) => {
                    for v in values {
                        if let Err(why) = a.kind.check(v) {
                            out.push(Problem::new(file, &tn, k, why.to_string()).value(v));
                        }
                    }
                }
            }
        }
    }
    // Cross-axis rules of every point, once the values themselves are right.
    if out.len() == before {
        match points(study, spec) {
            Err(msgs) => {
                for m in msgs {
                    out.push(Problem::new(file, &table, "", m));
                }
            }
            Ok(points) => ignored_axes(file, &table, spec, study, &points, out),
        }
    }

    // Scenes: generators, parameters, model files.
    if spec.scenes.is_empty()
        && !out
            .iter()
            .any(|p| p.table.starts_with(&table) && p.key == "scenes")
    {
        out.push(Problem::new(
            file,
            &table,
            "scenes",
            "no scenes: add [[study.scenes]] tables",
        ));
    }
    let mut seen = BTreeSet::new();
    for (scene, &j) in spec.scenes.iter().zip(&spec.scene_tables) {
        let tn = format!("{table} › scene {j} ({})", scene.generator);
        // A study that renders one view would run a path at its first view only: refused,
        // never silently narrowed.
        if !study.moves_camera()
            && scene
                .params
                .get(scenarios::path::CAMERA_PATH.name)
                .is_some()
            && seen.insert(format!("{tn} camera_path"))
        {
            out.push(Problem::new(
                file,
                &tn,
                scenarios::path::CAMERA_PATH.name,
                format!(
                    "the {} study renders one view per scene: a camera path runs in a `views` study",
                    spec.kind
                ),
            ));
        }
        for e in scene.check() {
            for p in scene_problems(file, &tn, e) {
                if seen.insert(p.to_string()) {
                    out.push(p);
                }
            }
        }
    }
}

/// An axis given for methods that read it at none of their points (its declaration says when
/// it is read: [`Axis::only_when`]): refused alike for one value or many, since a value no
/// point reads would name configurations that do not differ. Given in `method_axes.M`: M must
/// read it at one of its points; given in the study's `axes`: some method of the study must.
/// Where a point leaves an axis unread, its value is dropped from that point (empty cell, not in
/// the point key) and points that then coincide run once ([`crate::axes::Point::resolve`]).
fn ignored_axes(
    file: &str,
    table: &str,
    spec: &StudySpec,
    study: &dyn Study,
    points: &[PointSpec],
    out: &mut Vec<Problem>,
) {
    // (method, axis) → the settings that left it unread, or None once some point reads it.
    let mut unread: std::collections::BTreeMap<(String, &'static str), Option<BTreeSet<String>>> =
        Default::default();
    for p in points {
        for a in study.axes(&p.method) {
            if a.when.is_none() {
                continue;
            }
            let e = unread
                .entry((p.method.clone(), a.name()))
                .or_insert_with(|| Some(BTreeSet::new()));
            match (a.ignored_at(&p.point), e.as_mut()) {
                (None, _) => *e = None,
                (Some(with), Some(set)) => {
                    set.insert(with);
                }
                (Some(_), None) => {}
            }
        }
    }
    let never_read = |m: &str, axis: &str| -> Option<String> {
        unread
            .get(&(
                m.to_string(),
                study.axes(m).iter().find(|a| a.name() == axis)?.name(),
            ))?
            .as_ref()
            .map(|w| w.iter().cloned().collect::<Vec<_>>().join(", "))
    };
    let why = |axis: &str, m: &str, with: &str| {
        let w = study
            .axes(m)
            .iter()
            .find(|a| a.name() == axis)
            .and_then(|a| a.when)
            .expect("only axes with a condition are unread");
        format!(
            "axis {axis} has no effect on method {m} (with {with}): it is read only with {} = {}, so a value given for it would name configurations that do not differ; give it where it is read (with {} = {}) or drop it",
            w.axis,
            w.values.join(" | "),
            w.axis,
            w.values.join(" | "),
        )
    };
    for (m, over) in &spec.method_axes {
        for k in over.keys() {
            if let Some(with) = never_read(m, k) {
                out.push(Problem::new(
                    file,
                    &format!("{table} › method_axes.{m}"),
                    k,
                    why(k, m, &with),
                ));
            }
        }
    }
    let methods: BTreeSet<&str> = points.iter().map(|p| p.method.as_str()).collect();
    for k in spec.axes.keys() {
        let declaring: Vec<&str> = methods
            .iter()
            .copied()
            .filter(|m| !spec.method_axes.get(*m).is_some_and(|o| o.contains_key(k)))
            .filter(|m| study.axes(m).iter().any(|a| a.name() == k))
            .collect();
        let silent: Vec<(&str, String)> = declaring
            .iter()
            .filter_map(|m| never_read(m, k).map(|w| (*m, w)))
            .collect();
        if !declaring.is_empty() && silent.len() == declaring.len() {
            let (m, with) = &silent[0];
            out.push(Problem::new(
                file,
                &format!("{table} › axes"),
                k,
                why(k, m, with),
            ));
        }
    }
}

/// A scene error as problems at `table` (a check-mode `Many` holds several).
fn scene_problems(file: &str, table: &str, e: SceneError) -> Vec<Problem> {
    match e {
        SceneError::Many(v) => v
            .into_iter()
            .flat_map(|e| scene_problems(file, table, e))
            .collect(),
        SceneError::UnknownGenerator(g, known) => {
            vec![
                Problem::new(file, table, "generator", "unknown scene generator")
                    .value(g)
                    .known(known.split(", ")),
            ]
        }
        SceneError::OutOfRange {
            param, value, why, ..
        } => {
            let p = Problem::new(file, table, &param, why);
            vec![if value.is_empty() { p } else { p.value(value) }]
        }
        SceneError::WrongType {
            param, expected, ..
        } => vec![Problem::new(
            file,
            table,
            &param,
            format!("must be {expected}"),
        )],
        SceneError::UnknownParam { param, known, .. } => {
            vec![Problem::new(file, table, &param, "unknown scene parameter")
                .known(known.split(", ").filter(|s| !s.is_empty()))]
        }
        SceneError::Obj { path, why } => {
            vec![Problem::new(file, table, "path", format!("model file: {why}")).value(path)]
        }
        SceneError::ModelLine { path, line, why } => {
            vec![Problem::new(
                file,
                table,
                "path",
                format!("{path}:{line}: {why}"),
            )]
        }
        // A model a script fetches is not a suite problem: until it is fetched, its rows are
        // skipped with the command to run (`runner`).
        SceneError::ModelMissing { .. } => Vec::new(),
        SceneError::Gltf { path, why } => {
            vec![Problem::new(file, table, "path", format!("glTF file: {why}")).value(path)]
        }
        SceneError::CameraFile { path, line, why } => {
            let at = line.map(|l| format!(":{l}")).unwrap_or_default();
            vec![Problem::new(
                file,
                table,
                "path_file",
                format!("{path}{at}: {why}"),
            )]
        }
        other => vec![Problem::new(file, table, "", other.to_string())],
    }
}

/// The model files a suite's scenes read (`path` parameters), for `mfx list suites`.
pub fn models_needed(suite: &Suite) -> Vec<String> {
    let mut out = BTreeSet::new();
    for spec in &suite.studies {
        for s in &spec.scenes {
            if let Some(ParamValue::Str(p)) = s.params.get("path") {
                out.insert(p.clone());
            }
        }
    }
    out.into_iter().collect()
}
