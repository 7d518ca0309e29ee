//! The validation pass: every typo class a new user makes is refused before any GPU work, with
//! a message naming the file, the table, the key, the value and the alternatives; a valid suite
//! passes. (The CLI's exit code 2 and "nothing written" are tested in the root `tests/cli.rs`.)

use bench_core::check::check_suite;
use mfx::STUDIES;
use scenarios::{problem, Problem, Suite};

/// A one-study methods suite around `study` lines and `scene` lines.
fn suite(top: &str, study: &str, scene: &str) -> String {
    format!(
        "name = \"t\"\n{top}\n[[study]]\nkind = \"methods\"\n{study}\n[[study.scenes]]\n{scene}\n"
    )
}

/// All problems of a suite text: the parse's and the check's.
fn problems(text: &str) -> Vec<Problem> {
    bench_core::check::check_text(STUDIES, text, "typo.toml").1
}

/// Asserts exactly one problem mentions every word of `words`, and returns its text.
fn one(text: &str, words: &[&str]) -> String {
    let p = problems(text);
    let all = problem::report(&p);
    let hits: Vec<String> = p
        .iter()
        .map(|x| x.to_string())
        .filter(|m| words.iter().all(|w| m.contains(w)))
        .collect();
    assert_eq!(
        hits.len(),
        1,
        "want one problem with {words:?}, got:\n{all}"
    );
    assert!(
        hits[0].starts_with("typo.toml: "),
        "names the file: {}",
        hits[0]
    );
    hits[0].clone()
}

const PEEL: &str = "methods = [\"depth_peel\"]";
const QUADS: &str = "generator = \"quads\"";

#[test]
fn a_valid_suite_has_no_problem() {
    assert!(problems(&suite("", PEEL, QUADS)).is_empty());
    for (name, _) in scenarios::suite::BUILTIN {
        let s = Suite::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let p: Vec<Problem> = check_suite(STUDIES, &s)
            .into_iter()
            // The model suites need meshes copied into models/ (README): named, not hidden.
            .filter(|p| !(p.key == "path" && p.message.contains("file not found")))
            .collect();
        assert!(p.is_empty(), "{name}:\n{}", problem::report(&p));
    }
}

#[test]
fn a_misspelt_axis_is_named_with_the_axes_the_methods_declare() {
    let m = one(
        &suite("", &format!("{PEEL}\naxes = {{ max_layer = [4] }}"), QUADS),
        &["study 0 (methods) › axes", "'max_layer'"],
    );
    assert!(
        m.contains("no method of this study declares") && m.contains("max_layers"),
        "{m}"
    );
}

#[test]
fn a_misspelt_methods_key_and_an_empty_methods_list_are_errors() {
    let text = suite("", "method = [\"wboit\"]", QUADS);
    one(&text, &["'method'", "unknown key", "methods"]);
    one(&text, &["'methods'", "missing"]);
    one(
        &suite("", "methods = []", QUADS),
        &["'methods'", "is empty"],
    );
    let m = one(
        &suite("", "methods = [\"wboit\", \"dpeth_peel\"]", QUADS),
        &["dpeth_peel"],
    );
    assert!(
        m.contains("unknown method") && m.contains("depth_peel"),
        "{m}"
    );
}

#[test]
fn software_profile_typos_are_errors() {
    let top = "[software]\nmax_triangle = 10\nmax_samples = \"three\"";
    let text = suite(top, PEEL, QUADS);
    one(
        &text,
        &[
            "[software]",
            "'max_triangle'",
            "unknown key",
            "max_triangles",
        ],
    );
    one(
        &text,
        &["[software]", "'max_samples' = \"three\"", "integer"],
    );
}

#[test]
fn unknown_generators_parameters_and_bad_values_are_named() {
    one(
        &suite("", PEEL, "generator = \"quadz\""),
        &["'generator' = quadz", "quads"],
    );
    let m = one(
        &suite("", PEEL, "generator = \"quads\"\ndepth_complexty = 4"),
        &[
            "scene 0 (quads)",
            "'depth_complexty'",
            "unknown scene parameter",
        ],
    );
    assert!(m.contains("depth_complexity"), "lists the known ones: {m}");
    one(
        &suite("", PEEL, "generator = \"quads\"\ndepth_complexity = -3"),
        &["'depth_complexity' = -3", "1..=4096"],
    );
    // Every problem of one scene at once, not the first only.
    let p = problems(&suite(
        "",
        PEEL,
        "generator = \"quads\"\ndepth_complexity = -3\nalpah = 0.5",
    ));
    assert_eq!(p.len(), 2, "{}", problem::report(&p));
}

#[test]
fn an_axis_value_no_adapter_could_run_is_an_error_not_a_skipped_row() {
    one(
        &suite(
            "",
            &format!("{PEEL}\naxes = {{ max_layers = [0, 16] }}"),
            QUADS,
        ),
        &["'max_layers' = 0", "1..=4096", "depth_peel"],
    );
    // A value one method of the table takes and another does not points at method_axes.
    let m = one(
        &suite(
            "",
            "methods = [\"kbuffer_rmw\", \"linked_list\"]\naxes = { layers = [512] }",
            QUADS,
        ),
        &["'layers' = 512", "kbuffer_rmw"],
    );
    assert!(m.contains("method_axes.kbuffer_rmw"), "{m}");
    // A rule across axes (dof_near ≤ dof_far) is checked per point.
    one(
        &suite(
            "",
            &format!("{PEEL}\naxes = {{ effect = [\"dof\"], dof_near = [5.0], dof_far = [1.0] }}"),
            QUADS,
        ),
        &["dof_near ≤ dof_far"],
    );
}

/// A temp folder removed when the test ends, pass or fail (derefs to its path).
struct Tmp(tempfile::TempDir);
impl std::ops::Deref for Tmp {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        self.0.path()
    }
}
impl AsRef<std::path::Path> for Tmp {
    fn as_ref(&self) -> &std::path::Path {
        self.0.path()
    }
}
fn tmp_dir(prefix: &str) -> Tmp {
    Tmp(tempfile::Builder::new()
        .prefix(&format!("{prefix}-"))
        .tempdir()
        .expect("a temp folder"))
}
fn temp_dir(tag: &str) -> Tmp {
    tmp_dir(&format!("mfx-check-{tag}"))
}

#[test]
fn model_files_are_checked_missing_directory_no_faces_short_faces() {
    let d = temp_dir("obj");
    let obj = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    };
    let scene = |path: &str| format!("generator = \"obj\"\npath = \"{path}\"");
    one(
        &suite("", PEEL, &scene("/no/such/model.obj")),
        &["'path' = /no/such/model.obj", "file not found"],
    );
    one(
        &suite("", PEEL, &scene(&d.display().to_string())),
        &["'path'", "is a directory"],
    );
    let lines = obj(
        "lines.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\np 1\n",
    );
    let m = one(
        &suite("", PEEL, &scene(&lines)),
        &["'path'", "no triangles"],
    );
    assert!(m.contains("2 line and 1 point"), "{m}");
    let short = obj("short.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n");
    one(
        &suite("", PEEL, &scene(&short)),
        &["'path'", "short.obj:5: ", "face with 2 vertices"],
    );
    let ok = obj("ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert!(problems(&suite("", PEEL, &scene(&ok))).is_empty());
    // And building such a scene fails the same way (a render or an unchecked sweep).
    let e = scenarios::SceneSpec::new(
        "obj",
        scenarios::Params::new().with("path", scenarios::ParamValue::Str(short)),
    )
    .build()
    .unwrap_err()
    .to_string();
    assert!(e.contains("face with 2 vertices"), "{e}");
}

#[test]
fn unknown_study_kind_and_option_typos_are_named() {
    let text =
        "name = \"t\"\n[[study]]\nkind = \"method\"\n[[study.scenes]]\ngenerator = \"quads\"\n";
    let m = one(text, &["'kind' = method", "unknown study kind"]);
    assert!(m.contains("methods"), "{m}");
    let text = "name = \"t\"\n[[study]]\nkind = \"geometry\"\nraster_chek = true\n[[study.scenes]]\ngenerator = \"mesh\"\n";
    let m = one(text, &["'raster_chek'", "unknown key"]);
    assert!(m.contains("raster_check"), "{m}");
}

#[test]
fn every_problem_is_reported_at_once() {
    let text = "name = \"t\"\nbogus = 1\n[software]\nmax_triangle = 1\n[[study]]\nkind = \"methods\"\nmethods = [\"nope\"]\naxes = { max_layer = [1] }\n[[study.scenes]]\ngenerator = \"quadz\"\n";
    let p = problems(text);
    assert_eq!(
        p.len(),
        5,
        "unknown top-level key, unknown [software] key, and the study's three:\n{}",
        problem::report(&p)
    );
    let text = text
        .replace("bogus = 1\n", "")
        .replace("[software]\nmax_triangle = 1\n", "");
    let p = problems(&text);
    assert_eq!(
        p.len(),
        3,
        "unknown method, unknown axis, unknown generator:\n{}",
        problem::report(&p)
    );
}

/// An axis given only where it is never read (its declaration says when it is) would name
/// configurations that do not differ: refused alike for one value or many, naming the method
/// and the setting. Where some point reads it, the points that do not drop it (next test).
#[test]
fn an_axis_no_point_reads_is_refused_for_one_value_or_many() {
    for values in ["[4, 8]", "[8]"] {
        let m = one(
            &suite(
                "",
                &format!("methods = [\"linked_list\"]\naxes = {{ layers = {values} }}"),
                QUADS,
            ),
            &[
                "'layers'",
                "no effect on method linked_list (with pool=counted)",
            ],
        );
        assert!(m.contains("study 0 (methods) › axes"), "{m}");
        let m = one(
            &suite(
                "",
                &format!("methods = [\"kbuffer_rmw\", \"linked_list\"]\nmethod_axes = {{ linked_list = {{ layers = {values} }} }}"),
                QUADS,
            ),
            &["'layers'", "with pool=counted"],
        );
        assert!(m.contains("method_axes.linked_list"), "{m}");
    }
    // Read somewhere: by another method of the study, or by the method at another setting.
    for study in [
        "methods = [\"kbuffer_rmw\", \"linked_list\"]\naxes = { layers = [4, 8] }",
        "methods = [\"kbuffer_rmw\", \"linked_list\"]\naxes = { layers = [8] }",
        "methods = [\"linked_list\"]\naxes = { pool = [\"counted\", \"fixed\"], layers = [4, 8], pool_slack = [0, 50] }",
        "methods = [\"linked_list\"]\naxes = { aa = [\"none\", \"msaa4\"], aa_capture = [\"sample\", \"coverage\"] }",
        &format!("{PEEL}\naxes = {{ effect = [\"transparency\", \"translucency\"], sigma = [0.5, 2.0] }}"),
    ] {
        let p = problems(&suite("", study, QUADS));
        assert!(p.is_empty(), "{study}:\n{}", problem::report(&p));
    }
    // The effects' own parameters: sigma is read by translucency and fresnel only.
    one(
        &suite(
            "",
            &format!("{PEEL}\naxes = {{ effect = [\"transparency\"], sigma = [0.5] }}"),
            QUADS,
        ),
        &["'sigma'", "depth_peel (with effect=transparency)"],
    );
}

/// Where a point leaves an axis unread its value is in neither its key nor its row, and points
/// that then coincide run once: the linked list's counted pool once, the fixed pool per layers.
#[test]
fn an_unread_axis_leaves_the_point_key_and_the_row_and_its_points_collapse() {
    let text = suite(
        "",
        "methods = [\"linked_list\"]\naxes = { pool = [\"counted\", \"fixed\"], layers = [4, 8] }",
        QUADS,
    );
    let (Some(s), p) = bench_core::check::check_text(STUDIES, &text, "t.toml") else {
        panic!("the suite parses");
    };
    assert!(p.is_empty(), "{}", problem::report(&p));
    let spec = &s.studies[0];
    let study = bench_core::study::by_kind(STUDIES, spec.kind).unwrap();
    let points = bench_core::study::points(study, spec).unwrap();
    let labels: Vec<String> = points.iter().map(|p| p.given().label()).collect();
    assert_eq!(points.len(), 3, "{labels:?}");
    let counted: Vec<_> = points
        .iter()
        .filter(|p| {
            p.given()
                .get("pool")
                .is_some_and(|v| v.to_string() == "counted")
        })
        .collect();
    assert_eq!(counted.len(), 1, "{labels:?}");
    assert!(counted[0].given().get("layers").is_none(), "{labels:?}");
    assert!(
        counted[0].point.recorded().get("layers").is_none(),
        "no layers cell"
    );
    let fixed = points
        .iter()
        .find(|p| {
            p.given()
                .get("pool")
                .is_some_and(|v| v.to_string() == "fixed")
        })
        .unwrap();
    assert!(
        fixed.point.recorded().get("layers").is_some(),
        "the fixed pool reads layers"
    );
}

/// A problem in `[timing]`, `[software]` or the top level does not hide the study's and the
/// scene's: every table's problems come at once, each once.
#[test]
fn problems_in_timing_software_and_top_level_do_not_hide_the_studies() {
    let text = "name = \"t\"\nresolutions = [[0, 64]]\n[timing]\nmin_samples = 10\nmax_samples = 5\n[software]\nmax_noise = 2.0\n[[study]]\nkind = \"methods\"\nmethods = [\"depth_pel\"]\n[[study.scenes]]\ngenerator = \"quads\"\ndepth_complexity = 0\n";
    let p = problems(text);
    let all = problem::report(&p);
    for (table, key) in [
        ("top level", "resolutions"),
        ("[timing]", "min_samples"),
        ("[software]", "max_noise"),
        ("study 0 (methods)", "methods"),
        ("study 0 (methods) › scene 0 (quads)", "depth_complexity"),
    ] {
        let n = p
            .iter()
            .filter(|x| x.table == table && x.key == key)
            .count();
        assert_eq!(n, 1, "{table} '{key}' once in:\n{all}");
    }
    assert_eq!(p.len(), 5, "{all}");
}

/// The suite example in ARCHITECTURE.md is a valid suite (docs that drift are refused here), and
/// the same text with one axis misspelt is not.
#[test]
fn the_architecture_suite_example_is_valid() {
    let doc = include_str!("../ARCHITECTURE.md");
    let start = doc
        .find("```toml\n")
        .expect("ARCHITECTURE.md has a toml example")
        + 8;
    let len = doc[start..].find("```").expect("the example ends");
    let example = &doc[start..start + len];
    let p = problems(example);
    assert!(p.is_empty(), "{}", problem::report(&p));
    let typo = example.replace("max_layers", "max_layer");
    assert!(!problems(&typo).is_empty(), "a misspelt axis is refused");
}

#[test]
fn sessions_out_of_range_or_with_interleave_are_refused() {
    let zero = one(&suite("[timing]\nsessions = 0", PEEL, QUADS), &["sessions"]);
    assert!(zero.contains('0'), "{zero}");
    let both = one(
        &suite("[timing]\nsessions = 3\ninterleave = true", PEEL, QUADS),
        &["sessions", "interleave"],
    );
    assert!(both.contains("[timing]"), "{both}");
    assert!(problems(&suite("[timing]\nsessions = 3", PEEL, QUADS)).is_empty());
}

#[test]
fn the_seeds_suites_check_without_their_models_and_skip_naming_the_fetch_script() {
    // Tests run in bench-core/, where models/ is absent: the Dragon is "not fetched", which is
    // not a suite problem (its rows are skipped naming the script).
    let seeds: Vec<&str> = scenarios::suite::BUILTIN
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| n.starts_with("seeds-"))
        .collect();
    // One per source setup, seeds-kbuffer-flush (the stand-ins' SPwH, too slow to run inside
    // seeds-kbuffer's budget) and seeds-volume (§6.3's applications on a generated mesh).
    assert_eq!(
        seeds.len(),
        8,
        "one seeds suite per source setup, seeds-kbuffer-flush and seeds-volume: {seeds:?}"
    );
    for name in seeds {
        let s = Suite::load(name).unwrap();
        let p = check_suite(STUDIES, &s);
        assert!(p.is_empty(), "{name}:\n{}", problem::report(&p));
        assert!(
            s.software.is_some(),
            "{name} has a [software] profile for CI"
        );
    }
    let e = scenarios::SceneSpec::new(
        "obj",
        scenarios::Params::new().with(
            "path",
            scenarios::ParamValue::Str("models/dragon_vrip.ply.gz".into()),
        ),
    )
    .build()
    .unwrap_err()
    .to_string();
    assert!(e.contains("bash scripts/fetch-dragon.sh"), "{e}");
}
