//! The CLI's contract with scripts: a bad suite or bad arguments exit 2 before any GPU work and
//! write nothing; `mfx check` reports every problem; a valid suite checks clean.

use std::process::{Command, Output};

use schema::Status;

fn mfx(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mfx"))
        .args(args)
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
        )
        .env("CI", "true")
        .output()
        .expect("mfx runs")
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr)
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
fn tmp(name: &str) -> Tmp {
    tmp_dir(&format!("mfx-cli-{name}"))
}

/// Each typo class of a new user, as a suite file.
const TYPOS: &[(&str, &str, &str)] = &[
    (
        "axis",
        "[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\"]\naxes = { max_layer = [4] }\n[[study.scenes]]\ngenerator = \"quads\"\n",
        "'max_layer'",
    ),
    (
        "methods-key",
        "[[study]]\nkind = \"methods\"\nmethod = [\"wboit\"]\n[[study.scenes]]\ngenerator = \"quads\"\n",
        "'method'",
    ),
    (
        "empty-methods",
        "[[study]]\nkind = \"methods\"\nmethods = []\n[[study.scenes]]\ngenerator = \"quads\"\n",
        "is empty",
    ),
    (
        "software",
        "[software]\nmax_triangle = 10\n[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\"]\n[[study.scenes]]\ngenerator = \"quads\"\n",
        "'max_triangle'",
    ),
    (
        "scene-param",
        "[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\"]\n[[study.scenes]]\ngenerator = \"quads\"\ndepth_complexity = -1\n",
        "'depth_complexity' = -1",
    ),
    (
        "missing-obj",
        "[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\"]\n[[study.scenes]]\ngenerator = \"obj\"\npath = \"/no/such.obj\"\n",
        "file not found",
    ),
    (
        "zero-layers",
        "[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\"]\naxes = { max_layers = [0] }\n[[study.scenes]]\ngenerator = \"quads\"\n",
        "'max_layers' = 0",
    ),
];

#[test]
fn every_typo_class_exits_2_naming_the_key_and_writes_nothing() {
    let d = tmp("typos");
    for (name, suite, word) in TYPOS {
        let file = d.join(format!("{name}.toml"));
        std::fs::write(&file, format!("name = \"{name}\"\n{suite}")).unwrap();
        let f = file.to_str().unwrap();
        let out = d.join(format!("{name}-out"));
        for args in [
            vec!["check", f],
            vec!["sweep", f, "--out", out.to_str().unwrap(), "--no-report"],
        ] {
            let o = mfx(&args);
            let t = text(&o);
            assert_eq!(o.status.code(), Some(2), "{name}: {args:?}\n{t}");
            assert!(
                t.contains(word) && t.contains(f),
                "{name}: {args:?} names {word} and the file:\n{t}"
            );
        }
        assert!(
            !out.exists(),
            "{name}: a refused sweep wrote {}",
            out.display()
        );
    }
}

#[test]
fn render_refuses_a_misspelt_axis_and_an_unknown_scene_parameter() {
    let d = tmp("render");
    let png = d.join("x.png");
    let png = png.to_str().unwrap();
    let o = mfx(&[
        "render",
        "--scene",
        "quads",
        "--method",
        "depth_peel",
        "--axis",
        "max_layer=2",
        "--png",
        png,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("'max_layer'") && text(&o).contains("max_layers"),
        "{}",
        text(&o)
    );
    let o = mfx(&[
        "render",
        "--scene",
        "quads",
        "--param",
        "depth_complexty=3",
        "--png",
        png,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("depth_complexty"), "{}", text(&o));
    assert!(!std::path::Path::new(png).exists());
}

#[test]
fn render_sizes_are_checked_like_a_suites_and_exit_2_before_any_gpu_work() {
    let d = tmp("render-size");
    let png = d.join("x.png");
    let png = png.to_str().unwrap();
    let max = scenarios::suite::MAX_SIDE;
    for (opt, v) in [
        ("--width", (max + 1).to_string()),
        ("--width", "0".to_string()),
        ("--height", "100000".to_string()),
    ] {
        let o = mfx(&["render", "--scene", "quads", opt, &v, "--png", png]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{opt} {v}: {t}");
        assert!(
            t.contains(&format!("{opt} {v}")) && t.contains(&format!("1..={max}")),
            "names the option and the limit: {t}"
        );
    }
    // A camera file's size is held to the same limit.
    let cam = d.join("cam.json");
    let o = mfx(&[
        "render",
        "--scene",
        "quads",
        "--width",
        "8",
        "--height",
        "8",
        "--camera-out",
        cam.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let json = std::fs::read_to_string(&cam).unwrap();
    std::fs::write(&cam, json.replace("\"width\": 8", "\"width\": 0")).unwrap();
    let o = mfx(&[
        "render",
        "--scene",
        "quads",
        "--camera-in",
        cam.to_str().unwrap(),
        "--png",
        png,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("width 0 is out of range"), "{}", text(&o));
    assert!(!std::path::Path::new(png).exists());
}

#[test]
fn a_mesh_that_covers_no_pixel_is_a_warning_not_silence() {
    // Three collinear vertices: a finite extent (normalisable) and a triangle of no area.
    let d = tmp("no-pixel");
    let obj = d.join("line.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    let cam = d.join("cam.json");
    let o = mfx(&[
        "render",
        "--obj",
        obj.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--camera-out",
        cam.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning") && err.contains("covers no pixel"),
        "{err}"
    );
}

#[test]
fn a_mesh_at_1e38_is_placed_in_view_not_collapsed() {
    // The file: in f32 the normalising scale underflowed to 0, world_from_object was
    // all zeros and every image was empty, "matching" an empty truth.
    let d = tmp("huge");
    let obj = d.join("huge.obj");
    std::fs::write(
        &obj,
        "v -1e38 -1e38 0\nv 1e38 -1e38 0\nv 0 1e38 0\nf 1 2 3\n",
    )
    .unwrap();
    let cam = d.join("cam.json");
    let o = mfx(&[
        "render",
        "--obj",
        obj.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--camera-out",
        cam.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(!text(&o).contains("covers no pixel"), "{}", text(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cam).unwrap()).unwrap();
    let m = &json["world_from_object"][0];
    let scale = m[0][0].as_f64().unwrap();
    assert!(
        (scale * 1e38 - 1.0 / 2f64.sqrt()).abs() < 1e-6,
        "x scale 1/radius (radius √2 · 1e38): {m}"
    );
}

#[test]
fn check_reports_the_problems_of_every_table_at_once() {
    let d = tmp("every-table");
    let file = d.join("three.toml");
    std::fs::write(
        &file,
        "name = \"three\"\nbogus = 1\n[timing]\nmax_noise = 5\n[[study]]\nkind = \"methods\"\nmethods = [\"depth_pel\"]\n[[study.scenes]]\ngenerator = \"quadz\"\n",
    )
    .unwrap();
    let o = mfx(&["check", file.to_str().unwrap()]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    for word in ["'bogus'", "[timing]: 'max_noise'", "= depth_pel", "= quadz"] {
        assert!(t.contains(word), "{word} in:\n{t}");
    }
}

#[test]
fn builtin_suites_check_clean_and_list_says_what_they_are() {
    let o = mfx(&["check", "smoke", "default", "effects", "stability_ci"]);
    assert!(o.status.success(), "{}", text(&o));
    // Four suites and the papers files (checked with every `mfx check`).
    assert_eq!(text(&o).matches("ok: ").count(), 5, "{}", text(&o));
    let o = mfx(&["list", "suites"]);
    let t = text(&o);
    for name in ["geometry-models", "shadows-bunny", "smoke"] {
        assert!(t.contains(name), "list suites names {name}:\n{t}");
    }
    assert!(t.contains("needs models/stanford-bunny.obj"), "{t}");
    let o = mfx(&["list", "methods"]);
    assert!(
        text(&o).contains("axis max_layers (default 64; an integer in 1..=4096)"),
        "{}",
        text(&o)
    );
}

#[test]
fn a_timing_override_is_checked_like_the_suites_own_keys_before_any_gpu_work() {
    let d = tmp("timing");
    for (arg, word) in [
        ("setle=false", "'setle'"),
        ("settle=maybe", "not a TOML value"),
        ("settle=3", "must be true or false"),
        ("cold=1", "must be true or false"),
        ("max_noise=2", "'max_noise' = 2"),
        ("sessions", "must be KEY=VALUE"),
    ] {
        let out = d.join("out");
        let o = mfx(&[
            "sweep",
            "smoke",
            "--timing",
            arg,
            "--out",
            out.to_str().unwrap(),
            "--no-report",
        ]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "--timing {arg}\n{t}");
        assert!(
            t.contains(word) && t.contains("--timing"),
            "--timing {arg}:\n{t}"
        );
        assert!(
            !out.exists(),
            "--timing {arg}: a refused sweep wrote its folder"
        );
    }
    let o = mfx(&[
        "sweep",
        "smoke",
        "--texture-memory",
        "shared",
        "--no-report",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("pooled, dedicated"), "{}", text(&o));
}

#[test]
fn a_timing_override_reaches_every_row_and_the_texture_memory_is_recorded() {
    let d = tmp("timing-ok");
    let out = d.join("run");
    let o = mfx(&[
        "sweep",
        "smoke",
        "--timing",
        "settle=true",
        "--timing",
        "max_samples=2",
        "--timing",
        "cold=true",
        "--texture-memory",
        "dedicated",
        "--out",
        out.to_str().unwrap(),
        "--no-report",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let mut rd = csv::Reader::from_path(out.join("runs.csv")).unwrap();
    let h = rd.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (rule, mem, samples) = (col("timing_rule"), col("texture_memory"), col("samples"));
    let mut n = 0;
    for r in rd.records() {
        let r = r.unwrap();
        assert!(
            r[rule].contains("GPU settled before each point") && r[rule].contains("cold: L2"),
            "{}",
            &r[rule]
        );
        assert_eq!(&r[mem], "dedicated");
        assert!(r[samples].parse::<usize>().unwrap() <= 2);
        n += 1;
    }
    assert!(n > 0);
}

/// Every file under a folder, relative, sorted.
fn tree(d: &std::path::Path) -> Vec<String> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(d).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(
                tree(&p)
                    .into_iter()
                    .map(|s| format!("{}/{s}", p.file_name().unwrap().to_string_lossy())),
            );
        } else {
            out.push(p.file_name().unwrap().to_string_lossy().to_string());
        }
    }
    out.sort();
    out
}

#[test]
fn compare_writes_only_where_told() {
    let d = tmp("compare-writes");
    let reference = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/results/reference/2026-12-02-h200-shadows-bunny/runs.csv"
    );
    let (a, b) = (d.join("a"), d.join("b"));
    for x in [&a, &b] {
        std::fs::create_dir_all(x).unwrap();
        std::fs::copy(reference, x.join("runs.csv")).unwrap();
    }
    let before = tree(&d);
    let o = mfx(&["compare", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(
        tree(&d),
        before,
        "compare without --html wrote into the runs it read"
    );
    let html = d.join("page");
    let o = mfx(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--html",
        html.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(html.join("compare.html").is_file());
    assert_eq!(tree(&a), tree(&d.join("a")));
    assert!(!b.join("report").exists());
}

/// Methods of the rows of a runs.csv.
fn methods_of(csv_path: &std::path::Path) -> Vec<(String, String)> {
    let mut rd = csv::Reader::from_path(csv_path).unwrap();
    let h = rd.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (m, k) = (col("method"), col("point_key"));
    rd.records()
        .map(|r| {
            let r = r.unwrap();
            (r[m].to_string(), r[k].to_string())
        })
        .collect()
}

#[test]
fn a_filter_runs_exactly_the_matching_points_the_dry_run_lists() {
    let d = tmp("filter");
    // The dry run lists the points and runs nothing.
    let out = d.join("dry");
    let o = mfx(&[
        "sweep",
        "smoke",
        "--filter",
        "wboit",
        "--filter",
        "*shells*",
        "--dry-run",
        "--out",
        out.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(!out.exists(), "a dry run wrote its folder");
    let listed: Vec<&str> = t
        .lines()
        .filter_map(|l| l.strip_prefix("  "))
        .filter(|k| !k.contains("|floor_"))
        .collect();
    // wboit on every scene, and every method on shells.
    assert!(listed.iter().any(|k| k.contains("|wboit|")), "{t}");
    assert!(
        listed
            .iter()
            .any(|k| k.contains("shells") && k.contains("|depth_peel|")),
        "{t}"
    );
    assert!(
        !listed
            .iter()
            .any(|k| !k.contains("shells") && !k.contains("|wboit|")),
        "{t}"
    );
    assert!(t.contains("nothing was run"), "{t}");

    // The sweep runs exactly those points (plus the floors of their groups).
    let out = d.join("run");
    let o = mfx(&[
        "sweep",
        "smoke",
        "--filter",
        "wboit",
        "--filter",
        "*shells*",
        "--timing",
        "max_samples=1",
        "--timing",
        "min_samples=1",
        "--no-flip",
        "--no-report",
        "--out",
        out.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(
        t.contains("mfx: group 1/"),
        "a line per group without a terminal:\n{t}"
    );
    assert!(t.contains("ETA"), "{t}");
    let rows = methods_of(&out.join("runs.csv"));
    let mut ran: Vec<&str> = rows
        .iter()
        .filter(|(m, _)| !m.starts_with("floor_"))
        .map(|(_, k)| k.as_str())
        .collect();
    let mut want = listed.clone();
    ran.sort();
    want.sort();
    assert_eq!(ran, want, "the rows are the listed points");

    // run.json says where and how it ran, and keeps every call of a resumed run.
    let o = mfx(&[
        "sweep",
        "smoke",
        "--filter",
        "wboit",
        "--filter",
        "*shells*",
        "--resume",
        "--no-report",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert!(j["host"]["cpu_cores"].as_u64().unwrap() > 0, "{j}");
    assert!(
        j["build"]["rustc"].as_str().unwrap().starts_with("rustc"),
        "{j}"
    );
    assert!(j["build"]["wgpu"].as_str().unwrap().contains('.'), "{j}");
    assert_eq!(
        j["software_profile"],
        serde_json::Value::Bool(false),
        "smoke has no [software]"
    );
    // The memory roofs, measured before the points on any adapter with timestamps (values are
    // the adapter's: lavapipe's say nothing of a GPU, so none is asserted).
    let roofs = j["roofs"]["points"].as_array().expect("roofs recorded");
    assert!(
        !roofs.is_empty() && j["roofs"]["l2_bytes"].as_u64() > Some(0),
        "{j}"
    );
    let calls = j["calls"].as_array().unwrap();
    assert_eq!(calls.len(), 2, "{j}");
    assert!(calls[1]["command_line"].to_string().contains("--resume"));

    // compare --json of the run with itself parses, every point SAME.
    let o = mfx(&[
        "compare",
        out.to_str().unwrap(),
        out.to_str().unwrap(),
        "--json",
        "--html",
        d.join("cmp").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let c: serde_json::Value = serde_json::from_slice(&o.stdout).expect("compare --json parses");
    let pts = c["points"].as_array().unwrap();
    assert!(!pts.is_empty());
    assert!(pts.iter().all(|p| p["time"]["verdict"] == "SAME"), "{c}");
}

#[test]
fn set_overrides_a_declared_axis_and_a_bad_one_is_refused() {
    let o = mfx(&["sweep", "smoke", "--set", "layers=2,8", "--dry-run"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.contains("layers=2") && t.contains("layers=8"), "{t}");
    assert!(
        !t.contains("layers=4"),
        "the suite's own value is replaced:\n{t}"
    );
    let d = tmp("set");
    for (arg, word) in [
        ("max_layers=0", "'max_layers' = 0"),
        ("no_such_axis=3", "'no_such_axis'"),
        ("layers", "AXIS=V1,V2"),
        ("layers=4,", "empty value"),
    ] {
        let out = d.join("out");
        let o = mfx(&[
            "sweep",
            "smoke",
            "--set",
            arg,
            "--out",
            out.to_str().unwrap(),
        ]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "--set {arg}\n{t}");
        assert!(t.contains(word) && t.contains("--set"), "--set {arg}:\n{t}");
        assert!(!out.exists());
    }
    let o = mfx(&["sweep", "smoke", "--filter", "no_such_method*", "--dry-run"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("matches no method"), "{}", text(&o));
}

#[test]
fn a_bad_baseline_is_refused_before_any_gpu_work() {
    let d = tmp("baseline");
    let out = d.join("out");
    let o = mfx(&[
        "sweep",
        "smoke",
        "--baseline",
        "no-such-baseline-here",
        "--out",
        out.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert!(
        t.contains("no-such-baseline-here") && t.contains("--baseline"),
        "{t}"
    );
    assert!(!t.contains("mfx: suite"), "no GPU was opened:\n{t}");
    assert!(!out.exists());
}

#[test]
fn list_json_parses_and_names_the_file_only_suites() {
    let o = mfx(&["list", "methods", "--json"]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("list --json parses");
    let m = j["methods"].as_array().unwrap();
    assert!(
        m.iter()
            .any(|m| m["name"] == "depth_peel" && m["exact"] == true),
        "{j}"
    );
    let o = mfx(&["list", "suites", "--json"]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("list --json parses");
    let names: Vec<&str> = j["suites"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    for n in ["smoke", "scaling", "perf-abuffer"] {
        assert!(names.contains(&n), "{n} in {names:?}");
    }
    let t = text(&mfx(&["list", "suites"]));
    assert!(t.contains("scaling") && t.contains("(file only)"), "{t}");
}

#[test]
fn a_gltf_scene_with_blend_and_mask_materials_is_judged_against_the_truth() {
    let d = tmp("gltf");
    let glb = scenarios::gltf::write_example(&d, true).unwrap();
    let suite = d.join("gltf.toml");
    std::fs::write(
        &suite,
        format!(
            "name = \"gltf\"\nresolutions = [[64, 64]]\n[timing]\nmin_samples = 1\nmax_samples = 1\nwarmup_frames = 1\nwarmup_max_frames = 1\n[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\", \"kbuffer_atomic\", \"wboit\"]\naxes = {{ max_layers = [64], layers = [4] }}\n[[study.scenes]]\ngenerator = \"gltf\"\npath = \"{}\"\n",
            glb.display()
        ),
    )
    .unwrap();
    let s = suite.to_str().unwrap();
    let o = mfx(&["check", s]);
    assert!(o.status.success(), "{}", text(&o));
    let out = d.join("run");
    let o = mfx(&["sweep", s, "--no-report", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let mut rd = csv::Reader::from_path(out.join("runs.csv")).unwrap();
    let h = rd.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (m, st, mt) = (col("method"), col("status"), col("matches_truth"));
    let mut peel = None;
    for r in rd.records() {
        let r = r.unwrap();
        assert_eq!(&r[st], Status::Ok.name(), "{r:?}");
        if &r[m] == "depth_peel" {
            peel = Some(r[mt].to_string());
        }
    }
    assert_eq!(
        peel.as_deref(),
        Some("true"),
        "exact depth peeling matches the f64 truth"
    );
    // A broken file is refused by check, naming glTF.
    std::fs::write(d.join("bad.glb"), b"glTF junk").unwrap();
    let bad = d.join("bad.toml");
    std::fs::write(
        &bad,
        format!(
            "name = \"bad\"\n[[study]]\nkind = \"methods\"\nmethods = [\"wboit\"]\n[[study.scenes]]\ngenerator = \"gltf\"\npath = \"{}\"\n",
            d.join("bad.glb").display()
        ),
    )
    .unwrap();
    let o = mfx(&["check", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("glTF file"), "{}", text(&o));
}

#[test]
fn backend_gles_lists_its_adapter_and_a_sweep_runs_on_it() {
    let o = mfx(&["list", "adapters", "--backend", "gles", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("list --json parses");
    let adapters = j["adapters"].as_array().unwrap();
    if adapters.is_empty() {
        // Only where EGL has no GLES 3 context; the warning names why.
        assert!(text(&o).contains("GLES"), "{}", text(&o));
        eprintln!("skipped: {}", text(&o));
        return;
    }
    assert!(
        adapters
            .iter()
            .all(|a| a["driver_info"].as_str().unwrap().contains("OpenGL ES")),
        "{j}"
    );
    let d = tmp("gles");
    let suite = d.join("gles.toml");
    std::fs::write(
        &suite,
        "name = \"gles\"\nresolutions = [[32, 32]]\n[timing]\nmin_samples = 1\nmax_samples = 1\nwarmup_frames = 1\nwarmup_max_frames = 1\n[[study]]\nkind = \"methods\"\nmethods = [\"wboit\", \"compute_abuffer\"]\n[[study.scenes]]\ngenerator = \"quads\"\ndepth_complexity = 3\n",
    )
    .unwrap();
    let out = d.join("run");
    let o = mfx(&[
        "sweep",
        suite.to_str().unwrap(),
        "--backend",
        "gles",
        "--no-report",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let mut rd = csv::Reader::from_path(out.join("runs.csv")).unwrap();
    let h = rd.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (m, st, b, mt) = (
        col("method"),
        col("status"),
        col("backend"),
        col("matches_truth"),
    );
    let mut abuffer = None;
    for r in rd.records() {
        let r = r.unwrap();
        assert_eq!(&r[b], "gles", "{r:?}");
        assert_eq!(&r[st], Status::Ok.name(), "{r:?}");
        if &r[m] == "compute_abuffer" {
            abuffer = Some(r[mt].to_string());
        }
    }
    assert_eq!(
        abuffer.as_deref(),
        Some("true"),
        "the exact compute A-buffer matches the f64 truth on GLES"
    );
}

#[test]
fn compare_of_runs_with_no_common_point_exits_2_and_its_help_says_what_base_and_new_are() {
    // Two committed runs of different suites (same schema): not one point_key in common.
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/results/reference");
    let a = format!("{root}/2026-12-02-h200-effects/runs.csv");
    let b = format!("{root}/2026-12-02-h200-shadows-bunny/runs.csv");
    let o = mfx(&["compare", &a, &b]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("no point in common") && text(&o).contains("nothing to compare"),
        "{}",
        text(&o)
    );
    let h = text(&mfx(&["compare", "--help"]));
    assert!(
        h.contains("<BASE>") && h.contains("The run compared against"),
        "{h}"
    );
    assert!(
        h.contains("<NEW>") && h.contains("ratios are NEW / BASE"),
        "{h}"
    );
}
