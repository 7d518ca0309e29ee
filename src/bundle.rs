//! `mfx bundle RUN`: a run as one attachable file (`runs.parquet`, `run.json`, samples, the
//! summary, the report, the FLIP gallery, `RUN.md`), which `mfx report` and `mfx compare` read
//! where they read a run folder; and `mfx dataset`: every run under a folder stacked into one
//! Parquet file for history queries.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use mfx_table::bundle;

use crate::usage;

/// Files of the run folder copied into the bundle as they are, where present.
const AS_IS: &[&str] = &["run.json", "samples.csv", "samples.csv.gz", "RUN.md"];
/// Folders copied whole (the FLIP gallery the report shows).
const FOLDERS: &[&str] = &["flip"];

/// Every file under `dir`, as (path relative to `base` with `/`, path on disk), sorted.
fn files_under(base: &Path, dir: &Path, out: &mut Vec<(String, PathBuf)>) -> Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()?;
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files_under(base, &p, out)?;
        } else if p.is_file() {
            let rel = p.strip_prefix(base).unwrap_or(&p);
            let name = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy())
                .collect::<Vec<_>>()
                .join("/");
            out.push((name, p));
        }
    }
    Ok(())
}

/// The default bundle file of a run folder: `<folder name>.mfx.tar.gz` here.
fn default_out(run: &Path) -> PathBuf {
    let name = run
        .canonicalize()
        .ok()
        .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "run".into());
    PathBuf::from(format!("{name}.mfx.tar.gz"))
}

/// Writes the bundle of run folder `run`; returns its path. The run folder is only read: the
/// Parquet file, summary and report are made in a temporary folder.
pub fn bundle(run: &Path, out: Option<&Path>) -> Result<PathBuf> {
    if !run.is_dir() {
        return Err(usage(format!("{}: not a run folder", run.display())));
    }
    let table = mfx_table::in_folder(run).ok_or_else(|| {
        usage(format!(
            "{}: holds neither runs.csv nor runs.parquet",
            run.display()
        ))
    })?;
    let out = out
        .map(Path::to_path_buf)
        .unwrap_or_else(|| default_out(run));
    let stage = tempfile::Builder::new().prefix("mfx-bundle-").tempdir()?;
    let st = stage.path();
    let mut files: Vec<(String, PathBuf)> = Vec::new();
    for name in AS_IS {
        let p = run.join(name);
        if p.is_file() {
            std::fs::copy(&p, st.join(name)).with_context(|| format!("copying {}", p.display()))?;
            files.push((name.to_string(), st.join(name)));
        }
    }
    for name in FOLDERS {
        let from = run.join(name);
        if from.is_dir() {
            let mut found = Vec::new();
            files_under(run, &from, &mut found)?;
            for (rel, p) in found {
                let to = st.join(&rel);
                std::fs::create_dir_all(to.parent().expect("a file in a folder"))?;
                std::fs::copy(&p, &to).with_context(|| format!("copying {}", p.display()))?;
                files.push((rel, to));
            }
        }
    }
    // runs.parquet: made from runs.csv (with run.json in its metadata), or the folder's own.
    let parquet = st.join(mfx_table::RUNS_PARQUET);
    if table.file_name().is_some_and(|n| n == mfx_table::RUNS_CSV) {
        std::fs::copy(&table, st.join(mfx_table::RUNS_CSV))?;
        let w = mfx_table::write_runs_parquet(st)?;
        if !w.text_fallback.is_empty() {
            eprintln!("mfx: runs.parquet: {}", w.describe());
        }
        std::fs::remove_file(st.join(mfx_table::RUNS_CSV))?;
    } else {
        std::fs::copy(&table, &parquet)?;
    }
    files.push((mfx_table::RUNS_PARQUET.into(), parquet.clone()));
    // The summary and the report, from the bundle's own files (so they are what a reader of the
    // bundle would make).
    let runs = report::Runs::load(&parquet)?;
    let summary = st.join("summary.md");
    std::fs::write(&summary, report::summary_text(&runs))?;
    files.push(("summary.md".into(), summary));
    report::build(st, None).context("the bundle's report")?;
    let mut reported = Vec::new();
    files_under(st, &st.join("report"), &mut reported)?;
    files.extend(reported);
    let left_out: Vec<String> = ["images"]
        .iter()
        .filter(|d| run.join(d).is_dir())
        .map(|d| format!("{d}/ (per-point images of --save-images; copy the run folder for them)"))
        .collect();
    let mut names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    names.sort();
    let manifest = serde_json::json!({
        "format": bundle::FORMAT,
        "run": run.canonicalize().ok().and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned())),
        "made_by": format!("mfx {} ({})", env!("CARGO_PKG_VERSION"), bench_core::build_info::git_rev()),
        "rows": runs.rows.len(),
        "files": names,
        "left_out": left_out,
    });
    bundle::write(&out, &manifest, &files)?;
    Ok(out)
}

/// `mfx report BUNDLE`: unpacks the bundle into `out` (default: the bundle's path without
/// `.tar.gz`) and builds the report there. A folder that holds a `runs.csv` is a run of its
/// own and is refused.
pub fn report_of_bundle(
    path: &Path,
    out: Option<&Path>,
    baseline: Option<&str>,
) -> Result<PathBuf> {
    let dir = match out {
        Some(d) => d.to_path_buf(),
        None => {
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let stem = name
                .strip_suffix(".tar.gz")
                .or_else(|| name.strip_suffix(".tgz"))
                .unwrap_or(&name);
            let stem = if stem == name {
                format!("{name}.d")
            } else {
                stem.to_string()
            };
            path.with_file_name(stem)
        }
    };
    if dir.join(mfx_table::RUNS_CSV).is_file() {
        return Err(usage(format!(
            "{} holds a runs.csv (a run folder): unpack the bundle elsewhere with --out",
            dir.display()
        )));
    }
    bundle::extract(path, &dir)?;
    report::build(&dir, baseline).with_context(|| format!("report of {}", path.display()))
}

/// `mfx dataset ROOT --out FILE`: every run folder under `root` stacked into one Parquet file
/// (`mfx_table::stack`), each row with its `run_folder`; folders holding `merged_from.txt` are
/// merges of runs stored beside them and are left out unless `with_merged`.
pub fn dataset(root: &Path, out: &Path, with_merged: bool) -> Result<()> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
            .with_context(|| format!("reading {}", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_dir())
            .collect();
        entries.sort();
        if mfx_table::in_folder(dir).is_some() {
            out.push(dir.to_path_buf());
        }
        for p in entries {
            walk(&p, out)?;
        }
        Ok(())
    }
    if !root.is_dir() {
        return Err(usage(format!("{}: not a folder", root.display())));
    }
    let mut folders = Vec::new();
    walk(root, &mut folders)?;
    let mut tables = Vec::new();
    let mut sources = Vec::new();
    let mut merged = 0;
    for f in &folders {
        if !with_merged && f.join("merged_from.txt").is_file() {
            merged += 1;
            continue;
        }
        let rel = f.strip_prefix(root).unwrap_or(f).display().to_string();
        let path = mfx_table::in_folder(f).expect("found by walk");
        let t = mfx_table::read(&path)?;
        let run_json = std::fs::read_to_string(f.join("run.json"))
            .ok()
            .and_then(|j| serde_json::from_str::<serde_json::Value>(&j).ok());
        sources.push(
            serde_json::json!({"run_folder": rel, "rows": t.rows.len(), "run.json": run_json}),
        );
        tables.push((rel, t));
    }
    if tables.is_empty() {
        bail!(
            "{}: no run folder (runs.csv or runs.parquet) under it",
            root.display()
        );
    }
    let stacked = mfx_table::stack(&tables);
    let w = mfx_table::write_parquet(
        out,
        &stacked,
        &[(
            DATASET_SOURCES_KEY.into(),
            serde_json::Value::Array(sources).to_string(),
        )],
    )?;
    println!(
        "dataset: {} runs, {} rows, {} columns -> {}{}",
        tables.len(),
        stacked.rows.len(),
        stacked.header.len(),
        out.display(),
        if merged > 0 {
            format!("; left out {merged} merged folders (their rows are their inputs'; --with-merged keeps them)")
        } else {
            String::new()
        }
    );
    if !w.text_fallback.is_empty() {
        println!("{}", w.describe());
    }
    Ok(())
}

/// The dataset's metadata key listing its runs: `[{"run_folder", "rows", "run.json"}, …]`.
pub const DATASET_SOURCES_KEY: &str = "mfx.sources";
