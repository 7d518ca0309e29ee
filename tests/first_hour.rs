//! A new user's first hour (issue 44): `--filter` before `--set`, glTF files as users ship them
//! through every door (`render --model`, `mfx model`, a sweep), no EGL noise on stderr, usage
//! mistakes exit 2, a render too big for the host refused before it grows.

use std::path::Path;
use std::process::{Command, Output};

fn mfx_env(args: &[&str], xdg: bool) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mfx"));
    c.args(args).env("CI", "true");
    if xdg {
        c.env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
        );
    } else {
        c.env_remove("XDG_RUNTIME_DIR");
    }
    c.output().expect("mfx runs")
}

fn mfx(args: &[&str]) -> Output {
    mfx_env(args, true)
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr)
}

fn tmp(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("mfx-first-{name}-"))
        .tempdir()
        .unwrap()
}

#[test]
fn the_filter_comes_before_set_and_set_touches_only_methods_that_read_the_axis() {
    // The README's line: the k-buffers get layers 8 and 16; the linked list is not selected.
    let o = mfx(&[
        "sweep",
        "default",
        "--dry-run",
        "--filter",
        "kbuffer_*",
        "--set",
        "layers=8,16",
    ]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(
        t.contains("kbuffer_atomic|layers=16") && !t.contains("layers=32"),
        "{t}"
    );
    assert!(!t.contains("|linked_list|"), "{t}");
    // Without a filter: every method that reads layers gets it; the linked list's counted pool
    // does not read it, so its points name no layers.
    let o = mfx(&["sweep", "methods", "--dry-run", "--set", "layers=4,8"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let ll: Vec<&str> = t.lines().filter(|l| l.contains("|linked_list|")).collect();
    assert!(!ll.is_empty(), "{t}");
    assert!(ll.iter().all(|l| !l.contains("layers=")), "{ll:?}");
    // An axis no selected method reads is refused (exit 2), naming why.
    let o = mfx(&[
        "sweep",
        "default",
        "--dry-run",
        "--filter",
        "depth_peel",
        "--set",
        "layers=8",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("no selected method"), "{}", text(&o));
}

#[test]
fn no_xdg_runtime_dir_error_without_the_variable() {
    let o = mfx_env(&["list", "adapters"], false);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{}", text(&o));
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    assert!(!err.contains("error:"), "{err}");
}

#[test]
fn usage_mistakes_exit_2_like_other_bad_input() {
    for args in [
        vec!["render", "--scene", "quads"],
        vec!["render", "--png", "x.png"],
        vec![
            "render",
            "--scene",
            "quads",
            "--param",
            "depth_complexity",
            "--png",
            "x.png",
        ],
        vec![
            "render",
            "--scene",
            "quads",
            "--method",
            "depth_peel,wboit",
            "--png",
            "x.png",
        ],
    ] {
        let o = mfx(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o));
    }
    let help = text(&mfx(&["render", "--help"]));
    assert!(
        help.contains("--scene") && help.contains("mfx list scenes"),
        "{help}"
    );
    assert!(help.contains("--model") && help.contains("glTF"), "{help}");
}

#[test]
fn a_render_too_big_for_the_host_is_refused_before_it_grows() {
    let t = tmp("big");
    let png = t.path().join("big.png");
    let start = std::time::Instant::now();
    let o = mfx(&[
        "render",
        "--scene",
        "quads",
        "--width",
        "16384",
        "--height",
        "16384",
        "--png",
        png.to_str().unwrap(),
    ]);
    // 16384² at ≥ 128 B a pixel is 32 GiB: over this machine's memory (24 GiB) and a CI's.
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("GiB"), "{}", text(&o));
    assert!(
        start.elapsed().as_secs() < 20,
        "refused before any big allocation"
    );
    assert!(!png.exists());
}

/// `example.gltf` + `.bin`, `example-embedded.gltf` (data: URI) and `example.glb` in `d`.
fn gltf_twins(d: &Path) -> [std::path::PathBuf; 3] {
    use scenarios::gltf::{write_example_as, Form};
    [
        write_example_as(d, Form::Separate).unwrap(),
        write_example_as(d, Form::Embedded).unwrap(),
        write_example_as(d, Form::Glb).unwrap(),
    ]
}

#[test]
fn render_and_model_take_a_gltf_by_path_and_a_bad_accessor_is_refused_naming_it() {
    let t = tmp("gltfcli");
    let d = t.path();
    let files = gltf_twins(d);
    for f in &files {
        let o = mfx(&["model", f.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o));
        assert!(text(&o).contains("8 triangles"), "{}", text(&o));
        let png = d.join("x.png");
        for flag in ["--model", "--obj"] {
            let o = mfx(&[
                "render",
                flag,
                f.to_str().unwrap(),
                "--width",
                "32",
                "--height",
                "32",
                "--png",
                png.to_str().unwrap(),
            ]);
            assert!(o.status.success(), "{flag} {}: {}", f.display(), text(&o));
            assert!(text(&o).contains("matches"), "{}", text(&o));
        }
    }
    let sep = std::fs::read_to_string(&files[0]).unwrap();
    let bad = d.join("overrun.gltf");
    std::fs::write(&bad, sep.replace(r#""count":6,"#, r#""count":2000000000,"#)).unwrap();
    for args in [
        vec!["model", bad.to_str().unwrap()],
        vec![
            "render",
            "--model",
            bad.to_str().unwrap(),
            "--png",
            "never.png",
        ],
    ] {
        let o = mfx(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o));
        assert!(text(&o).contains("accessor 1"), "{}", text(&o));
    }
}

/// The issue-43 done-when: the embedded glTF of a small scene runs on lavapipe with the same
/// rows as its `.gltf` + `.bin` twin (and its `.glb`), outside the timing and file columns.
#[test]
fn an_embedded_gltf_sweeps_to_the_same_rows_as_its_gltf_bin_twin() {
    let t = tmp("gltftwins");
    let d = t.path();
    let files = gltf_twins(d);
    let scenes: String = files
        .iter()
        .map(|f| {
            format!(
                "[[study.scenes]]\ngenerator = \"gltf\"\npath = \"{}\"\n",
                f.display()
            )
        })
        .collect();
    let suite = d.join("twins.toml");
    std::fs::write(
        &suite,
        format!(
            "name = \"twins\"\nresolutions = [[48, 48]]\n[timing]\nmin_samples = 1\nmax_samples = 1\nwarmup_frames = 1\nwarmup_max_frames = 1\n[[study]]\nkind = \"methods\"\nmethods = [\"depth_peel\", \"linked_list\", \"compute_abuffer\", \"wboit\"]\n{scenes}"
        ),
    )
    .unwrap();
    let out = d.join("run");
    let o = mfx(&[
        "sweep",
        suite.to_str().unwrap(),
        "--no-report",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let mut rd = csv::Reader::from_path(out.join("runs.csv")).unwrap();
    let h = rd.headers().unwrap().clone();
    // What a row says about the picture and its fragments (not how long it took, nor the file).
    const SAME: &[&str] = &[
        "method",
        "status",
        "reason",
        "triangles",
        "vertices",
        "depth_complexity_max",
        "depth_complexity_mean",
        "true_fragments",
        "exact",
        "matches_truth",
        "rmse",
        "psnr_db",
        "max_abs_err",
        "bad_pixel_frac",
        "non_finite",
        "fragments_missing",
        "fragments_extra",
        "depth_tie_pixels",
        "layers_captured_max",
        "overflow_rate",
        "bytes_allocated",
    ];
    let idx: Vec<usize> = SAME
        .iter()
        .map(|c| {
            h.iter()
                .position(|x| x == *c)
                .unwrap_or_else(|| panic!("column {c}"))
        })
        .collect();
    let scene = h.iter().position(|x| x == "scene_label").unwrap();
    let mut by_file: std::collections::BTreeMap<String, Vec<Vec<String>>> = Default::default();
    for r in rd.records() {
        let r = r.unwrap();
        by_file
            .entry(r[scene].to_string())
            .or_default()
            .push(idx.iter().map(|&i| r[i].to_string()).collect());
    }
    assert_eq!(by_file.len(), 3, "{:?}", by_file.keys());
    let rows: Vec<&Vec<Vec<String>>> = by_file.values().collect();
    assert!(
        rows[0].len() >= 4 + 3,
        "every method and the floors: {:?}",
        rows[0]
    );
    assert!(
        rows[0]
            .iter()
            .all(|r| r[1] == schema::Status::Ok.to_string()),
        "{:?}",
        rows[0]
    );
    assert_eq!(rows[0], rows[1], "embedded vs separate");
    assert_eq!(rows[0], rows[2], "glb vs separate");
}
