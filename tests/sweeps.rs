//! Sweeps through the built binary: the ground truth and the method's own definition are both
//! reported, a run folder is never overwritten, a killed run resumes to the uninterrupted point
//! set, the commit recorded is mfx's own, and `mfx compare` calls what it sees.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output, Stdio};

fn cmd(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mfx"));
    c.args(args)
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
        )
        .env("CI", "true");
    c
}

fn mfx(args: &[&str]) -> Output {
    cmd(args).output().expect("mfx runs")
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr)
}

fn ok(args: &[&str]) -> String {
    let o = mfx(args);
    assert!(o.status.success(), "mfx {args:?}:\n{}", text(&o));
    text(&o)
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
    tmp_dir(&format!("mfx-sweeps-{name}"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The first number after `label` in `out`.
fn number_after(out: &str, label: &str) -> f64 {
    let at = out
        .find(label)
        .unwrap_or_else(|| panic!("no '{label}' in:\n{out}"))
        + label.len();
    let num: String = out[at..]
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || ".e-+".contains(*c))
        .collect();
    num.parse()
        .unwrap_or_else(|_| panic!("'{num}' after '{label}' in:\n{out}"))
}

/// rmse vs the ground truth and vs the method's own definition, as `mfx render` prints them.
fn render_errors(args: &[&str]) -> (f64, Option<f64>) {
    let png_dir = tmp_dir("mfx-sweeps-png");
    let png = png_dir.join("render.png");
    let mut all = vec![
        "render",
        "--width",
        "48",
        "--height",
        "48",
        "--png",
        s(&png),
    ];
    all.extend_from_slice(args);
    let out = ok(&all);
    let truth = out
        .split("vs the ground truth")
        .nth(1)
        .expect("a ground-truth line");
    let own = out
        .split("vs its own definition")
        .nth(1)
        .map(|t| number_after(t, "rmse"));
    (number_after(truth, "rmse"), own)
}

#[test]
fn render_reports_the_ground_truth_error_of_a_truncation_and_its_own_definition_apart() {
    let t = tmp("render");
    let (truth, own) = render_errors(&[
        "--scene",
        "quads",
        "--param",
        "depth_complexity=32",
        "--method",
        "depth_peel",
        "--axis",
        "max_layers=2",
        "--reference-png",
        s(&t.join("truth.png")),
        "--reference-k-png",
        s(&t.join("k.png")),
    ]);
    assert!(
        truth > 0.1,
        "2 of 32 layers against the ground truth: rmse {truth}"
    );
    assert!(own.expect("an own-definition line") < 1e-6, "{own:?}");
    // The two references differ: the ground truth is not the 2-layer composite.
    let (a, b) = (
        std::fs::read(t.join("truth.png")).unwrap(),
        std::fs::read(t.join("k.png")).unwrap(),
    );
    assert_ne!(a, b, "--reference-png wrote the truncated composite");
    for m in ["kbuffer_atomic", "kbuffer_rmw"] {
        let (truth, _) = render_errors(&[
            "--scene",
            "quads",
            "--param",
            "depth_complexity=16",
            "--method",
            m,
            "--axis",
            "layers=4",
        ]);
        assert!(
            truth > 0.01,
            "{m} k=4 of 16 layers: ground-truth rmse {truth}"
        );
    }
}

/// A suite of many quick points (16², one sample each) to interrupt.
const SUITE: &str = r#"
name = "resume-test"
description = "many small points"
resolutions = [[16, 16], [24, 16]]
[timing]
min_samples = 1
max_samples = 1
warmup_frames = 0
warmup_max_frames = 0
[[study]]
kind = "methods"
methods = ["depth_peel", "wboit", "linked_list", "kbuffer_atomic"]
[[study.scenes]]
generator = "quads"
depth_complexity = [1, 2, 3, 4, 5, 6]
"#;

/// runs.csv as (point_key → count) and its raw bytes.
fn points(dir: &Path) -> (BTreeMap<String, usize>, usize) {
    let mut r = csv::Reader::from_path(dir.join("runs.csv")).unwrap();
    let k = r
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == "point_key")
        .unwrap();
    let mut m = BTreeMap::new();
    let mut n = 0;
    for rec in r.records() {
        *m.entry(rec.unwrap()[k].to_string()).or_insert(0) += 1;
        n += 1;
    }
    (m, n)
}

fn data_lines(p: &Path) -> usize {
    std::fs::read_to_string(p)
        .map(|t| t.lines().count().saturating_sub(1))
        .unwrap_or(0)
}

#[test]
fn a_killed_sweep_resumes_to_the_uninterrupted_point_set_and_a_second_sweep_is_refused() {
    let t = tmp("resume");
    let suite = t.join("suite.toml");
    std::fs::write(&suite, SUITE).unwrap();
    let full = t.join("full");
    ok(&[
        "sweep",
        s(&suite),
        "--out",
        s(&full),
        "--no-report",
        "--no-flip",
    ]);
    let (want, n_full) = points(&full);
    assert_eq!(want.len(), n_full, "the uninterrupted run has duplicates");
    assert!(n_full >= 40, "{n_full} rows");

    // Refused without --resume/--force, and the first runs.csv is untouched.
    let before = std::fs::read(full.join("runs.csv")).unwrap();
    let o = mfx(&["sweep", s(&suite), "--out", s(&full), "--no-report"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--resume"), "{}", text(&o));
    assert_eq!(std::fs::read(full.join("runs.csv")).unwrap(), before);

    // SIGKILL part-way (no chance to clean up), then resume.
    let cut = t.join("cut");
    let mut child = cmd(&[
        "sweep",
        s(&suite),
        "--out",
        s(&cut),
        "--no-report",
        "--no-flip",
    ])
    .stdout(Stdio::null())
    .stderr(Stdio::null())
    .spawn()
    .unwrap();
    let csv = cut.join("runs.csv");
    let t0 = std::time::Instant::now();
    while data_lines(&csv) < 5 && t0.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let (partial, _) = points(&cut);
    assert!(
        !partial.is_empty() && partial.len() < want.len(),
        "killed after {} of {} rows: the kill did not land mid-run",
        partial.len(),
        want.len()
    );
    let out = ok(&[
        "sweep",
        s(&suite),
        "--out",
        s(&cut),
        "--resume",
        "--no-report",
        "--no-flip",
    ]);
    assert!(out.contains("resumed"), "{out}");
    let (got, n) = points(&cut);
    assert_eq!(got.len(), n, "the resumed runs.csv has duplicate points");
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        want.keys().collect::<Vec<_>>(),
        "resumed point set differs from the uninterrupted one"
    );
    // The samples of the resumed run belong to its rows, once each.
    let mut r = csv::Reader::from_path(cut.join("samples.csv")).unwrap();
    let k = r
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == "point_key")
        .unwrap();
    let mut per: BTreeMap<String, usize> = BTreeMap::new();
    for rec in r.records() {
        *per.entry(rec.unwrap()[k].to_string()).or_insert(0) += 1;
    }
    assert!(per.keys().all(|p| got.contains_key(p)));
    assert!(
        per.values().all(|&c| c == 1),
        "a point was sampled twice: {per:?}"
    );
}

fn git(dir: &Path, args: &[&str]) -> String {
    let o = Command::new("git")
        .args(args)
        .current_dir(dir)
        .env("GIT_AUTHOR_NAME", "t")
        .env("GIT_AUTHOR_EMAIL", "t@t")
        .env("GIT_COMMITTER_NAME", "t")
        .env("GIT_COMMITTER_EMAIL", "t@t")
        .output()
        .expect("git runs");
    assert!(o.status.success(), "git {args:?}: {}", text(&o));
    String::from_utf8_lossy(&o.stdout).trim().to_string()
}

/// A column of the first row of a runs.csv.
fn first_cell(csv_path: &Path, col: &str) -> String {
    let mut r = csv::Reader::from_path(csv_path).unwrap();
    let k = r.headers().unwrap().iter().position(|h| h == col).unwrap();
    r.records().next().unwrap().unwrap()[k].to_string()
}

#[test]
fn a_sweep_started_inside_another_repository_records_mfx_own_commit() {
    let Ok(o) = Command::new("git").arg("--version").output() else {
        eprintln!("no git here: nothing to check");
        return;
    };
    assert!(o.status.success());
    let other = tmp("otherrepo");
    git(&other, &["init", "-q"]);
    std::fs::write(other.join("f"), "x").unwrap();
    git(&other, &["add", "f"]);
    git(&other, &["commit", "-q", "-m", "x"]);
    let theirs = git(&other, &["rev-parse", "HEAD"]);
    let out = other.join("run");
    let o = cmd(&[
        "sweep",
        "smoke",
        "--out",
        s(&out),
        "--no-report",
        "--no-flip",
    ])
    .current_dir(&other)
    .output()
    .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let rev = first_cell(&out.join("runs.csv"), "git_rev");
    let ours = rev.trim_end_matches("+dirty");
    assert!(!ours.is_empty() && ours != "unknown", "git_rev '{rev}'");
    assert!(
        !theirs.starts_with(ours),
        "recorded the current directory's commit {theirs}"
    );
    // mfx's checkout, when this test runs from one, is where the commit comes from.
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    if let Ok(head) = Command::new("git")
        .args(["rev-parse", "HEAD"])
        .current_dir(here)
        .output()
    {
        if head.status.success() && std::env::var_os("MFX_GIT_REV").is_none() {
            let head = String::from_utf8_lossy(&head.stdout).trim().to_string();
            assert!(
                head.starts_with(ours),
                "git_rev {rev} is not mfx's HEAD {head}"
            );
        }
    }
    let manifest = std::fs::read_to_string(out.join("run.json")).unwrap();
    assert!(manifest.contains(ours), "run.json lacks the commit");
}

/// A copy of a runs.csv with every time column scaled.
fn scaled_copy(from: &Path, to: &Path, k: f64) {
    std::fs::create_dir_all(to).unwrap();
    let mut r = csv::Reader::from_path(from.join("runs.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let mut w = csv::Writer::from_path(to.join("runs.csv")).unwrap();
    w.write_record(&h).unwrap();
    for rec in r.records() {
        let rec = rec.unwrap();
        let cells: Vec<String> = h
            .iter()
            .zip(rec.iter())
            .map(|(c, v)| match v.parse::<f64>() {
                Ok(x)
                    if c.starts_with("gpu_ms")
                        && c != "gpu_ms_rel_noise"
                        && c != "gpu_ms_rel_ci" =>
                {
                    format!("{}", x * k)
                }
                _ => v.to_string(),
            })
            .collect();
        w.write_record(&cells).unwrap();
    }
    w.flush().unwrap();
    if from.join("samples.csv").is_file() {
        let mut r = csv::Reader::from_path(from.join("samples.csv")).unwrap();
        let h = r.headers().unwrap().clone();
        let mut w = csv::Writer::from_path(to.join("samples.csv")).unwrap();
        w.write_record(&h).unwrap();
        for rec in r.records() {
            let rec = rec.unwrap();
            let cells: Vec<String> = h
                .iter()
                .zip(rec.iter())
                .map(|(c, v)| match v.parse::<f64>() {
                    Ok(x) if c == "gpu_ms" => format!("{}", x * k),
                    _ => v.to_string(),
                })
                .collect();
            w.write_record(&cells).unwrap();
        }
        w.flush().unwrap();
    }
}

/// A copy of a run folder whose samples are steady: each point's GPU samples become its median
/// times 1 + 0.2 % × (sample mod 5 − 2), so a comparison of this copy decides on the arithmetic
/// alone, whatever the CPU's load did to the real samples.
fn steady_copy(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    std::fs::copy(from.join("runs.csv"), to.join("runs.csv")).unwrap();
    let mut medians = std::collections::HashMap::new();
    let mut r = csv::Reader::from_path(from.join("runs.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    let (key, med) = (col("point_key"), col("gpu_ms_median"));
    for rec in r.records() {
        let rec = rec.unwrap();
        if let Ok(m) = rec[med].parse::<f64>() {
            medians.insert(rec[key].to_string(), m);
        }
    }
    let mut r = csv::Reader::from_path(from.join("samples.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    let (key, sample, gpu) = (col("point_key"), col("sample"), col("gpu_ms"));
    let mut w = csv::Writer::from_path(to.join("samples.csv")).unwrap();
    w.write_record(&h).unwrap();
    for rec in r.records() {
        let rec = rec.unwrap();
        let mut cells: Vec<String> = rec.iter().map(str::to_string).collect();
        if let (Some(m), Ok(i)) = (medians.get(&rec[key]), rec[sample].parse::<u64>()) {
            cells[gpu] = format!("{}", m * (1.0 + 0.002 * ((i % 5) as f64 - 2.0)));
        }
        w.write_record(&cells).unwrap();
    }
    w.flush().unwrap();
}

/// Enough samples per point for the test to decide: lavapipe's 16² frames are noisy enough
/// that 8 a side do not always separate a 1.5× shift.
const COMPARE_SUITE: &str = r#"
name = "compare-test"
description = "a few points, 30 samples each"
resolutions = [[16, 16]]
[timing]
min_samples = 30
max_samples = 30
warmup_frames = 1
warmup_max_frames = 1
[[study]]
kind = "methods"
methods = ["depth_peel", "wboit"]
[[study.scenes]]
generator = "quads"
depth_complexity = [2, 4]
"#;

#[test]
fn compare_calls_a_run_same_as_itself_slower_at_1_5x_and_refuses_mixed_schemas() {
    let t = tmp("compare");
    let suite = t.join("suite.toml");
    std::fs::write(&suite, COMPARE_SUITE).unwrap();
    let a = t.join("a");
    ok(&[
        "sweep",
        s(&suite),
        "--out",
        s(&a),
        "--no-report",
        "--no-flip",
    ]);
    let same = ok(&["compare", s(&a), s(&a)]);
    assert!(same.contains("SAME"), "{same}");
    for bad in ["FASTER", "SLOWER", "UNSURE"] {
        assert!(
            !same.contains(&format!("| {bad}")),
            "self-comparison says {bad}:\n{same}"
        );
    }
    let b = t.join("b");
    scaled_copy(&a, &b, 1.5);
    let o = mfx(&["compare", s(&a), s(&b), "--fail-on-slower", "5%"]);
    let slow = text(&o);
    assert!(slow.contains("SLOWER"), "{slow}");
    for other in ["| SAME", "| FASTER"] {
        assert!(
            !slow.contains(other),
            "×1.5 copy has a {other} point:\n{slow}"
        );
    }
    // With steady samples every point of a ×1.5 copy is SLOWER, as the rule says it must be.
    let (sa, sb) = (t.join("steady-a"), t.join("steady-b"));
    steady_copy(&a, &sa);
    scaled_copy(&sa, &sb, 1.5);
    let steady = text(&mfx(&["compare", s(&sa), s(&sb)]));
    let points = steady
        .lines()
        .filter(|l| l.starts_with("| methods"))
        .count();
    let slower = steady.lines().filter(|l| l.contains("| SLOWER")).count();
    assert!(
        points > 0 && slower == points,
        "{slower} of {points} SLOWER:\n{steady}"
    );
    // On real samples from a loaded CPU a point's bootstrap CI can be wider than ×1.5: then it
    // is UNSURE, and only with the noise named (never silently undecided).
    for line in slow.lines().filter(|l| l.contains("| UNSURE")) {
        assert!(
            line.contains(schema::Flag::Noisy.name()) && line.contains("not significant"),
            "an UNSURE point without its reason: {line}"
        );
    }
    assert_eq!(
        o.status.code(),
        Some(1),
        "--fail-on-slower exits 1:\n{slow}"
    );

    // A schema-1 runs.csv (the column set before this schema) is refused, naming both.
    let old = t.join("old");
    std::fs::create_dir_all(&old).unwrap();
    let csv = std::fs::read_to_string(a.join("runs.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    let schema_col = header.split(',').position(|h| h == "schema").unwrap();
    let mut out = String::from(header) + "\n";
    for l in lines {
        let mut cells: Vec<&str> = l.split(',').collect();
        if cells.len() > schema_col {
            cells[schema_col] = "1";
        }
        out += &(cells.join(",") + "\n");
    }
    std::fs::write(old.join("runs.csv"), out).unwrap();
    let o = mfx(&["compare", s(&old), s(&a)]);
    assert_ne!(o.status.code(), Some(0), "{}", text(&o));
    assert!(text(&o).contains("schema"), "{}", text(&o));
}
