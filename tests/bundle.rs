//! A run as one file, and its typed twin, through the built binary: `mfx sweep smoke` (lavapipe)
//! writes runs.parquet beside runs.csv with the same rows and the Slurm job on every row;
//! `mfx bundle` packs it; `mfx compare BUNDLE RUN` finds every point SAME; `mfx report BUNDLE`
//! writes a report; `mfx dataset` stacks it; `--balance-from` shards it without losing a point.

use std::path::Path;
use std::process::{Command, Output};

fn mfx(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mfx"))
        .args(args)
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
        )
        .env("CI", "true")
        .env("SLURM_JOB_ID", "4711")
        .env("SLURM_ARRAY_JOB_ID", "4700")
        .env("SLURM_ARRAY_TASK_ID", "11")
        .output()
        .expect("mfx runs")
}

fn ok(args: &[&str]) -> String {
    let o = mfx(args);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "mfx {args:?}:\n{text}");
    String::from_utf8_lossy(&o.stdout).to_string()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The points `mfx sweep … --dry-run` lists (indented point-key lines).
fn dry_points(out: &str) -> Vec<String> {
    let mut v: Vec<String> = out
        .lines()
        .filter(|l| l.starts_with("  "))
        .map(|l| l.trim().to_string())
        .collect();
    v.sort();
    v
}

#[test]
fn a_bundled_smoke_run_compares_same_with_its_folder_and_reports() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    ok(&[
        "sweep",
        "smoke",
        "--out",
        s(&run),
        "--no-report",
        "--no-flip",
    ]);

    // runs.parquet holds runs.csv's rows; every row says which job ran it.
    let csv = mfx_table::read(&run.join("runs.csv")).unwrap();
    let pq = mfx_table::read(&run.join("runs.parquet")).unwrap();
    assert_eq!(pq.header, csv.header);
    assert_eq!(pq.rows.len(), csv.rows.len());
    let job = csv.col(schema::cols::SLURM_JOB_ID.name).unwrap();
    assert!(csv.rows.iter().all(|r| r[job] == "4711"));
    let run_json: serde_json::Value = serde_json::from_str(
        pq.meta(mfx_table::RUN_JSON_KEY)
            .expect("run.json in the metadata"),
    )
    .unwrap();
    assert_eq!(run_json["job"]["slurm_array_task_id"], "11");
    assert!(
        run_json["gpu"]["source"]
            .as_str()
            .unwrap()
            .starts_with("wgpu adapter info"),
        "lavapipe has no NVML: {}",
        run_json["gpu"]
    );

    let bundle = t.path().join("run.mfx.tar.gz");
    let out = ok(&["bundle", s(&run), "--out", s(&bundle)]);
    assert!(out.contains("bundle:"), "{out}");
    assert!(mfx_table::bundle::is_bundle(&bundle));
    assert!(!run.join("report").exists(), "the run folder is only read");

    // The bundle against the folder it came from: every point SAME, or (lavapipe's few, noisy
    // samples leave some UNSURE) the very same samples: ratio 1, p = 1, equal medians.
    let cmp: serde_json::Value =
        serde_json::from_str(&ok(&["compare", s(&bundle), s(&run), "--json"])).unwrap();
    let points = cmp["points"].as_array().unwrap();
    assert!(!points.is_empty());
    for p in points {
        let t = &p["time"];
        let equal = t["ratio"] == 1.0 && t["p"] == 1.0 && t["n_base"] == t["n_new"];
        assert!(t["verdict"] == "SAME" || equal, "{p}");
        assert_eq!(p["base_median_ms"], p["new_median_ms"], "{p}");
    }
    for k in ["only_base", "only_new", "errors", "status_changes"] {
        assert!(cmp[k].as_array().unwrap().is_empty(), "{k}: {}", cmp[k]);
    }
    assert!(
        cmp["base"]["samples_csv"]
            .as_str()
            .unwrap()
            .contains("run.mfx.tar.gz"),
        "the side names the bundle: {}",
        cmp["base"]
    );

    // A report from the bundle alone, unpacked beside it.
    let out = ok(&["report", s(&bundle)]);
    let page = t.path().join("run.mfx/report/index.html");
    assert!(page.is_file(), "{out}");
    assert!(std::fs::read_to_string(&page).unwrap().contains("<html"));
    assert!(t.path().join("run.mfx/summary.md").is_file());

    // The dataset of the folder holding the run (the unpacked bundle is another run folder).
    let all = t.path().join("all.parquet");
    let out = ok(&["dataset", s(t.path()), "--out", s(&all)]);
    assert!(out.contains("2 runs"), "{out}");
    let d = mfx_table::read(&all).unwrap();
    assert_eq!(d.rows.len(), 2 * csv.rows.len());
    assert_eq!(d.header[0], mfx_table::RUN_FOLDER);

    // Shards balanced by the run's times: together, exactly the unsharded points.
    let whole = dry_points(&ok(&["sweep", "smoke", "--dry-run"]));
    let mut shards = Vec::new();
    for i in 0..3 {
        let out = ok(&[
            "sweep",
            "smoke",
            "--dry-run",
            "--shard",
            &format!("{i}/3"),
            "--balance-from",
            s(&run),
        ]);
        assert!(out.contains("shards balanced by"), "{out}");
        shards.extend(dry_points(&out));
    }
    shards.sort();
    assert_eq!(shards, whole);
}
