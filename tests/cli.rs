//! The CLI's contract with scripts: a bad suite or bad arguments exit 2 before any GPU work and
//! write nothing; `mfx check` reports every problem; a valid suite checks clean.

use std::path::PathBuf;
use std::process::{Command, Output};

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

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mfx-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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
fn builtin_suites_check_clean_and_list_says_what_they_are() {
    let o = mfx(&["check", "smoke", "default", "effects", "stability_ci"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(text(&o).matches("ok: ").count(), 4, "{}", text(&o));
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
            r[rule].contains("GPU settled before each point"),
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
