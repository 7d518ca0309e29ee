//! `mfx merge`: shard and machine outputs into one tidy `runs.csv`.
//!
//! Inputs are run folders (holding `runs.csv`), folders of run folders (one level down, e.g. a
//! Slurm job's `shard-*/`), or CSV files. The merge refuses inputs whose header or schema
//! version differs (naming both files), and never drops a row silently: a point seen twice
//! (same `point_key`, `adapter` and `backend`) keeps its first row in `runs.csv` and every later
//! one goes to `duplicates.csv` with the file it came from, and is listed in the summary.
//! Saved images (`images/`, from `mfx sweep --save-images`) are copied beside the merged CSV.
//!
//! Across GPUs (issue 33): each input's `run.json` holds the calibration set measured on its GPU
//! before its points ([`crate::manifest::GpuCalibration`]). The merge writes each GPU's ratio to
//! the inputs' median to `gpu_calibration.csv`, and when the GPUs differ it says by how much: a
//! difference between points measured on different GPUs that lies within that spread may be
//! the GPUs, not the methods.

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::record::cols;
use crate::{CoreError, Result};

/// A row seen more than once.
#[derive(Clone, Debug)]
pub struct Duplicate {
    pub point_key: String,
    pub adapter: String,
    pub backend: String,
    /// The limits profile (`adapter` where the column is empty): another profile on the same
    /// adapter is another platform, not a duplicate.
    pub limits: String,
    /// File of the row that was kept, and of this later one.
    pub kept_from: PathBuf,
    pub from: PathBuf,
}

/// One input's GPU on the calibration set.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuRatio {
    pub file: PathBuf,
    pub adapter: String,
    pub pci_bus_id: String,
    pub canary_ms: f64,
    /// `canary_ms` over the median of every input's.
    pub ratio: f64,
}

/// What a merge did.
#[derive(Debug, Default)]
pub struct Merged {
    pub files: Vec<PathBuf>,
    pub rows: usize,
    pub duplicates: Vec<Duplicate>,
    pub images_copied: usize,
    /// `image_file`s of merged rows that no input folder held (e.g. a run copied without its
    /// `images/`): reported, never silently left dangling.
    pub images_missing: Vec<String>,
    pub out_csv: PathBuf,
    /// Inputs whose `run.json` holds a calibration set; empty when none does.
    pub gpus: Vec<GpuRatio>,
    /// Inputs without one (older runs, software adapters, CSV files without a run folder).
    pub uncalibrated: usize,
    /// Columns of `runs.parquet` written as text because a cell is off its declared type (one
    /// line each; empty when every column is typed).
    pub parquet_fallback: String,
}

/// The key of the merged `runs.parquet`'s metadata that lists the inputs, each with its
/// `run.json` (`[{"file": …, "run.json": {…} | null}, …]`).
pub const MERGED_FROM_KEY: &str = "mfx.merged_from";

impl Merged {
    /// The largest `|ratio − 1|` over the calibrated GPUs (0 with fewer than two).
    pub fn gpu_spread(&self) -> f64 {
        self.gpus
            .iter()
            .map(|g| (g.ratio - 1.0).abs())
            .fold(0.0, f64::max)
    }

    /// More than one GPU (by PCI bus id, else adapter name) among the calibrated inputs.
    pub fn several_gpus(&self) -> bool {
        let id = |g: &GpuRatio| format!("{}|{}", g.adapter, g.pci_bus_id);
        self.gpus.iter().any(|g| id(g) != id(&self.gpus[0]))
    }
}

impl Merged {
    /// A human summary: files, rows, and each duplicate (never a silent drop).
    pub fn summary(&self) -> String {
        let mut s = format!(
            "merged {} files, {} rows -> {}",
            self.files.len(),
            self.rows,
            self.out_csv.display()
        );
        if !self.parquet_fallback.is_empty() {
            s.push_str(&format!("\nruns.parquet: {}", self.parquet_fallback));
        }
        if self.images_copied > 0 {
            s.push_str(&format!("; {} images copied", self.images_copied));
        }
        if let Some(first) = self.images_missing.first() {
            s.push_str(&format!(
                "\n{} rows name an image that no input folder holds (first: {first}); the \
                 report cannot compare those points' images",
                self.images_missing.len()
            ));
        }
        if self.several_gpus() {
            s.push_str(&format!(
                "\nGPUs differ on the calibration set by up to {:.1} % (gpu_calibration.csv): a \
                 difference between points measured on different GPUs within ±{:.1} % may be the \
                 GPUs, not the methods",
                self.gpu_spread() * 100.0,
                self.gpu_spread() * 100.0
            ));
        }
        if !self.gpus.is_empty() && self.uncalibrated > 0 {
            s.push_str(&format!(
                "\n{} inputs have no calibration set in run.json: their GPUs cannot be compared",
                self.uncalibrated
            ));
        }
        if !self.duplicates.is_empty() {
            s.push_str(&format!(
                "\n{} duplicate points (same point_key, adapter, backend and limits): kept the first row \
                 of each in runs.csv, wrote the others to duplicates.csv:",
                self.duplicates.len()
            ));
            for d in &self.duplicates {
                s.push_str(&format!(
                    "\n  {} on {} ({}): kept {}, duplicate in {}",
                    d.point_key,
                    d.adapter,
                    d.backend,
                    d.kept_from.display(),
                    d.from.display()
                ));
            }
        }
        s
    }
}

/// The runs tables an input names: a `runs.csv` or `runs.parquet` file, a run folder, or the
/// run folders one level below it (sorted, so the merge order is stable). A folder's table is
/// its `runs.csv`, else its `runs.parquet` (`mfx_table::in_folder`).
pub fn input_files(input: &Path) -> Result<Vec<PathBuf>> {
    if input.is_file() {
        return Ok(vec![input.to_path_buf()]);
    }
    if !input.is_dir() {
        return Err(CoreError::Io(format!(
            "{}: no such file or folder",
            input.display()
        )));
    }
    if let Some(direct) = mfx_table::in_folder(input) {
        return Ok(vec![direct]);
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir(input)
        .map_err(|e| CoreError::Io(format!("{}: {e}", input.display())))?
        .filter_map(|e| e.ok())
        .filter_map(|e| mfx_table::in_folder(&e.path()))
        .collect();
    found.sort();
    if found.is_empty() {
        return Err(CoreError::Io(format!(
            "{}: holds no runs.csv or runs.parquet (neither directly nor in a sub-folder)",
            input.display()
        )));
    }
    Ok(found)
}

fn io(p: &Path, e: impl std::fmt::Display) -> CoreError {
    CoreError::Io(format!("{}: {e}", p.display()))
}

/// Merges `inputs` into `out/runs.csv` (+ `out/duplicates.csv` when there are duplicates, and
/// `out/images/`). The output folder must not be one of the inputs' folders.
pub fn merge(inputs: &[PathBuf], out: &Path) -> Result<Merged> {
    if inputs.is_empty() {
        return Err(CoreError::Param("merge: no input folders given".into()));
    }
    let mut files = Vec::new();
    for i in inputs {
        for f in input_files(i)? {
            if !files.contains(&f) {
                files.push(f);
            }
        }
    }
    let out_csv = out.join("runs.csv");
    if let Ok(abs_out) = out_csv.canonicalize() {
        if files
            .iter()
            .any(|f| f.canonicalize().ok().as_ref() == Some(&abs_out))
        {
            return Err(CoreError::Param(format!(
                "merge: the output {} is also an input; choose another --out",
                out_csv.display()
            )));
        }
    }
    // Read everything first: nothing is written unless every input is compatible.
    let mut header: Option<(Vec<String>, PathBuf)> = None;
    let mut schema: Option<(String, PathBuf)> = None;
    let mut tables: Vec<(PathBuf, Vec<Vec<String>>)> = Vec::new();
    let mut run_jsons: Vec<Option<String>> = Vec::new();
    for f in &files {
        let t = mfx_table::read(f).map_err(|e| CoreError::Io(e.to_string()))?;
        let h = t.header;
        let schema_col = h
            .iter()
            .position(|c| c == cols::SCHEMA.name)
            .ok_or_else(|| {
                CoreError::Schema(format!(
                    "{}: not an mfx runs table (no 'schema' column)",
                    f.display()
                ))
            })?;
        match &header {
            None => header = Some((h.clone(), f.clone())),
            Some((h0, f0)) if *h0 != h => {
                let diff = h0
                    .iter()
                    .zip(&h)
                    .position(|(a, b)| a != b)
                    .map(|i| format!("column {} is '{}' vs '{}'", i + 1, h0[i], h[i]))
                    .unwrap_or_else(|| format!("{} vs {} columns", h0.len(), h.len()));
                return Err(CoreError::Schema(format!(
                    "cannot merge {} and {}: different CSV headers ({diff}); re-run one of \
                     them with the same mfx version",
                    f0.display(),
                    f.display()
                )));
            }
            _ => {}
        }
        for (n, rec) in t.rows.iter().enumerate() {
            let v = rec.get(schema_col).cloned().unwrap_or_default();
            match &schema {
                None => schema = Some((v, f.clone())),
                Some((v0, f0)) if *v0 != v => {
                    return Err(CoreError::Schema(format!(
                        "cannot merge {} (schema version {v0}) and {} (schema version {v}, \
                         row {}): different CSV schema versions. Their columns mean different \
                         things (schema 1 had fixed reps and errors against the truncated \
                         definition; see results/README.md), so no row is converted: merge runs \
                         of one schema, or rerun the older suite with this build",
                        f0.display(),
                        f.display(),
                        n + 2
                    )));
                }
                _ => {}
            }
        }
        // The run.json beside the table, else the one a runs.parquet carries.
        let dir = f.parent().unwrap_or(Path::new("."));
        run_jsons.push(
            std::fs::read_to_string(dir.join(crate::manifest::MANIFEST_FILE))
                .ok()
                .or_else(|| {
                    t.metadata
                        .iter()
                        .find(|(k, _)| k == mfx_table::RUN_JSON_KEY)
                        .map(|(_, v)| v.clone())
                }),
        );
        tables.push((f.clone(), t.rows));
    }
    let (header, _) = header.expect("at least one file");
    let col = |name: &str| header.iter().position(|c| c == name);
    let (kp, ka, kb, kl) = (
        col(cols::POINT_KEY.name),
        col(cols::ADAPTER.name),
        col(cols::BACKEND.name),
        col(cols::LIMITS.name),
    );

    std::fs::create_dir_all(out).map_err(|e| io(out, e))?;
    let mut w = csv::Writer::from_path(&out_csv).map_err(|e| io(&out_csv, e))?;
    w.write_record(&header).map_err(|e| io(&out_csv, e))?;
    let mut seen: HashMap<(String, String, String, String), PathBuf> = HashMap::new();
    let mut dups: Vec<(PathBuf, Vec<String>, Duplicate)> = Vec::new();
    let mut merged_rows: Vec<Vec<String>> = Vec::new();
    let cell =
        |r: &[String], i: Option<usize>| i.and_then(|i| r.get(i)).cloned().unwrap_or_default();
    for (f, recs) in &tables {
        for r in recs {
            let limits = match cell(r, kl) {
                l if l.is_empty() => "adapter".to_string(),
                l => l,
            };
            let key = (cell(r, kp), cell(r, ka), cell(r, kb), limits);
            if let Some(kept) = seen.get(&key) {
                dups.push((
                    f.clone(),
                    r.clone(),
                    Duplicate {
                        point_key: key.0,
                        adapter: key.1,
                        backend: key.2,
                        limits: key.3,
                        kept_from: kept.clone(),
                        from: f.clone(),
                    },
                ));
                continue;
            }
            seen.insert(key, f.clone());
            w.write_record(r).map_err(|e| io(&out_csv, e))?;
            merged_rows.push(r.clone());
        }
    }
    w.flush().map_err(|e| io(&out_csv, e))?;
    let rows = merged_rows.len();
    let dup_csv = out.join("duplicates.csv");
    if dups.is_empty() {
        // A stale duplicates.csv from an earlier merge into the same folder would mislead.
        let _ = std::fs::remove_file(&dup_csv);
    } else {
        let mut w = csv::Writer::from_path(&dup_csv).map_err(|e| io(&dup_csv, e))?;
        let mut h = vec!["source_file".to_string()];
        h.extend(header.iter().cloned());
        w.write_record(&h).map_err(|e| io(&dup_csv, e))?;
        for (f, r, _) in &dups {
            let mut rec = vec![f.display().to_string()];
            rec.extend(r.iter().cloned());
            w.write_record(&rec).map_err(|e| io(&dup_csv, e))?;
        }
        w.flush().map_err(|e| io(&dup_csv, e))?;
    }
    let (gpus, uncalibrated) = gpu_ratios(&files, &run_jsons);
    let cal_csv = out.join("gpu_calibration.csv");
    if gpus.is_empty() {
        let _ = std::fs::remove_file(&cal_csv);
    } else {
        let mut w = csv::Writer::from_path(&cal_csv).map_err(|e| io(&cal_csv, e))?;
        w.write_record([
            "source_file",
            "adapter",
            "pci_bus_id",
            "canary_ms",
            "ratio_to_median",
        ])
        .map_err(|e| io(&cal_csv, e))?;
        for g in &gpus {
            w.write_record([
                g.file.display().to_string(),
                g.adapter.clone(),
                g.pci_bus_id.clone(),
                g.canary_ms.to_string(),
                g.ratio.to_string(),
            ])
            .map_err(|e| io(&cal_csv, e))?;
        }
        w.flush().map_err(|e| io(&cal_csv, e))?;
    }
    // The typed twin of the merged rows, with every input's run.json in its metadata.
    let inputs: Vec<serde_json::Value> = files
        .iter()
        .zip(&run_jsons)
        .map(|(f, j)| {
            serde_json::json!({
                "file": f.display().to_string(),
                "run.json": j.as_deref().and_then(|j| serde_json::from_str::<serde_json::Value>(j).ok()),
            })
        })
        .collect();
    let table = mfx_table::Table {
        header: header.clone(),
        rows: merged_rows,
        metadata: Vec::new(),
    };
    let written = mfx_table::write_parquet(
        &out.join(mfx_table::RUNS_PARQUET),
        &table,
        &[(
            MERGED_FROM_KEY.to_string(),
            serde_json::Value::Array(inputs).to_string(),
        )],
    )
    .map_err(|e| CoreError::Io(e.to_string()))?;
    let images_copied = copy_images(&files, out)?;
    let images_missing = missing_images(&out_csv, out)?;
    let mut log = std::fs::File::create(out.join("merged_from.txt")).map_err(|e| io(out, e))?;
    for f in &files {
        writeln!(log, "{}", f.display()).map_err(|e| io(out, e))?;
    }
    Ok(Merged {
        files,
        rows,
        duplicates: dups.into_iter().map(|(_, _, d)| d).collect(),
        images_copied,
        images_missing,
        out_csv,
        gpus,
        uncalibrated,
        parquet_fallback: written.describe(),
    })
}

/// Each input's calibration set (from its `run.json`) and its ratio to the median of all; and
/// how many inputs had none.
fn gpu_ratios(files: &[PathBuf], run_jsons: &[Option<String>]) -> (Vec<GpuRatio>, usize) {
    let mut gpus = Vec::new();
    let mut none = 0;
    for (f, j) in files.iter().zip(run_jsons) {
        match j
            .as_deref()
            .and_then(|j| serde_json::from_str::<crate::manifest::RunManifest>(j).ok())
            .and_then(|m| Some((m.calibration?, m.adapter)))
        {
            Some((c, a)) if c.canary_ms.is_finite() && c.canary_ms > 0.0 => gpus.push(GpuRatio {
                file: f.clone(),
                adapter: a.name,
                pci_bus_id: a.pci_bus_id,
                canary_ms: c.canary_ms,
                ratio: f64::NAN,
            }),
            _ => none += 1,
        }
    }
    let mut ms: Vec<f64> = gpus.iter().map(|g| g.canary_ms).collect();
    ms.sort_by(f64::total_cmp);
    if let Some(&m) = ms.get(ms.len() / 2) {
        // The lower median of an even count: a real GPU's time, not a mean of two.
        let m = if ms.len().is_multiple_of(2) {
            ms[ms.len() / 2 - 1]
        } else {
            m
        };
        for g in &mut gpus {
            g.ratio = g.canary_ms / m;
        }
    }
    (gpus, none)
}

/// Copies each input's `images/*` into `out/images/`. Image names hash the point key, adapter
/// and backend, so two inputs only share a name for a duplicate point (the first copy is kept).
fn copy_images(files: &[PathBuf], out: &Path) -> Result<usize> {
    let dst = out.join("images");
    let mut n = 0;
    for f in files {
        let src = f.parent().unwrap_or(Path::new(".")).join("images");
        if !src.is_dir() || src.canonicalize().ok() == dst.canonicalize().ok() {
            continue;
        }
        std::fs::create_dir_all(&dst).map_err(|e| io(&dst, e))?;
        for e in std::fs::read_dir(&src).map_err(|e| io(&src, e))? {
            let e = e.map_err(|e| io(&src, e))?;
            let target = dst.join(e.file_name());
            if e.path().is_file() && !target.exists() {
                std::fs::copy(e.path(), &target).map_err(|err| io(&target, err))?;
                n += 1;
            }
        }
    }
    Ok(n)
}

/// The `image_file` cells of a merged runs.csv that name no file under `out`.
fn missing_images(csv_path: &Path, out: &Path) -> Result<Vec<String>> {
    let mut rdr = csv::Reader::from_path(csv_path).map_err(|e| io(csv_path, e))?;
    let h = rdr.headers().map_err(|e| io(csv_path, e))?.clone();
    let Some(i) = h.iter().position(|c| c == cols::IMAGE_FILE.name) else {
        return Ok(Vec::new());
    };
    let mut missing = Vec::new();
    for r in rdr.records() {
        let r = r.map_err(|e| io(csv_path, e))?;
        let f = r.get(i).unwrap_or("");
        if !f.is_empty() && !out.join(f).is_file() {
            missing.push(f.to_string());
        }
    }
    Ok(missing)
}

/// The point keys of a runs table (CSV or Parquet), sorted (for shard/merge equality checks).
pub fn point_keys(path: &Path) -> Result<Vec<String>> {
    let t = mfx_table::read(path).map_err(|e| CoreError::Io(e.to_string()))?;
    let i = t
        .col(cols::POINT_KEY.name)
        .ok_or_else(|| CoreError::Schema(format!("{}: no point_key column", path.display())))?;
    let mut keys: Vec<String> = t.rows.into_iter().map(|mut r| r.swap_remove(i)).collect();
    keys.sort();
    Ok(keys)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let d = dir.join(name);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("runs.csv"), text).unwrap();
        d
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
        tmp_dir(&format!("mfx-merge-{name}"))
    }

    const H: &str = "schema,point_key,adapter,backend,status\n";

    /// A run.json for `dir` on `adapter` (bus `bus`) whose calibration set took `ms`.
    fn manifest(dir: &Path, adapter: &str, bus: &str, ms: Option<f64>) {
        let info = crate::manifest::AdapterInfo {
            name: adapter.into(),
            pci_bus_id: bus.into(),
            ..Default::default()
        };
        let mut m = crate::manifest::RunManifest::new(vec![], "s", "s", "", info, (0, 2));
        m.calibration = ms.map(|canary_ms| crate::manifest::GpuCalibration {
            set: crate::manifest::CALIBRATION_SET.into(),
            canary_ms,
            runs: 21,
        });
        m.write(dir).unwrap();
    }

    #[test]
    fn shards_on_two_gpus_record_each_gpus_ratio_and_say_how_far_they_differ() {
        let t = tmp("gpus");
        let a = write(&t, "a", &format!("{H}1,k1,H200,vulkan,ok\n"));
        let b = write(&t, "b", &format!("{H}1,k2,H200,vulkan,ok\n"));
        let c = write(&t, "c", &format!("{H}1,k3,H200,vulkan,ok\n"));
        manifest(&a, "H200", "0000:01:00.0", Some(1.00));
        manifest(&b, "H200", "0000:02:00.0", Some(1.08));
        manifest(&c, "H200", "0000:03:00.0", Some(1.02));
        let m = merge(&[a, b, c], &t.join("out")).unwrap();
        let r: Vec<f64> = m.gpus.iter().map(|g| g.ratio).collect();
        assert_eq!(r.len(), 3);
        assert!(
            (r[0] - 1.0 / 1.02).abs() < 1e-12 && (r[2] - 1.0).abs() < 1e-12,
            "{r:?}"
        );
        assert!((m.gpu_spread() - (1.08 / 1.02 - 1.0)).abs() < 1e-12);
        assert!(m.several_gpus());
        let s = m.summary();
        assert!(
            s.contains("GPUs differ on the calibration set by up to 5.9 %"),
            "{s}"
        );
        let csv = std::fs::read_to_string(t.join("out/gpu_calibration.csv")).unwrap();
        assert_eq!(csv.lines().count(), 4, "{csv}");
        // Shards of one GPU: ratios recorded, no cross-GPU warning.
        let t = tmp("gpu1");
        let a = write(&t, "a", &format!("{H}1,k1,H200,vulkan,ok\n"));
        let b = write(&t, "b", &format!("{H}1,k2,H200,vulkan,ok\n"));
        manifest(&a, "H200", "0000:01:00.0", Some(1.00));
        manifest(&b, "H200", "0000:01:00.0", Some(1.01));
        let m = merge(&[a, b], &t.join("out")).unwrap();
        assert!(!m.several_gpus() && !m.summary().contains("GPUs differ"));
        // An older run without the set: said, not guessed.
        let t = tmp("gpu0");
        let a = write(&t, "a", &format!("{H}1,k1,H200,vulkan,ok\n"));
        let b = write(&t, "b", &format!("{H}1,k2,H200,vulkan,ok\n"));
        manifest(&a, "H200", "0000:01:00.0", Some(1.00));
        manifest(&b, "H200", "0000:02:00.0", None);
        let m = merge(&[a, b], &t.join("out")).unwrap();
        assert_eq!(m.uncalibrated, 1);
        assert!(
            m.summary().contains("1 inputs have no calibration set"),
            "{}",
            m.summary()
        );
    }

    #[test]
    fn concatenates_and_reports_duplicates_without_dropping_them() {
        let t = tmp("dup");
        let a = write(
            &t,
            "a",
            &format!("{H}1,k1,gpu,vulkan,ok\n1,k2,gpu,vulkan,ok\n"),
        );
        let b = write(
            &t,
            "b",
            &format!("{H}1,k2,gpu,vulkan,failed\n1,k2,cpu,vulkan,ok\n"),
        );
        let m = merge(&[a, b.clone()], &t.join("out")).unwrap();
        assert_eq!(m.rows, 3, "k1, k2 on gpu, k2 on cpu");
        assert_eq!(m.duplicates.len(), 1);
        assert_eq!(m.duplicates[0].point_key, "k2");
        assert_eq!(m.duplicates[0].from, b.join("runs.csv"));
        let dup = std::fs::read_to_string(t.join("out/duplicates.csv")).unwrap();
        assert!(dup.contains("k2,gpu,vulkan,failed"), "{dup}");
        assert!(
            m.summary().contains("k2 on gpu (vulkan)"),
            "{}",
            m.summary()
        );
        let keys = point_keys(&t.join("out/runs.csv")).unwrap();
        assert_eq!(keys, ["k1", "k2", "k2"]);
    }

    #[test]
    fn a_parquet_run_merges_with_a_csv_run_into_a_typed_runs_parquet() {
        let t = tmp("parquet");
        let a = write(&t, "a", &format!("{H}3,k1,gpu,vulkan,ok\n"));
        // b holds only runs.parquet (a run read back from a bundle, or its CSV deleted).
        let b = write(
            &t,
            "b",
            &format!("{H}3,k2,gpu,vulkan,ok\n3,k3,gpu,vulkan,ok\n"),
        );
        manifest(&b, "H200", "0000:02:00.0", Some(1.0));
        mfx_table::write_runs_parquet(&b).unwrap();
        std::fs::remove_file(b.join("runs.csv")).unwrap();
        std::fs::remove_file(b.join("run.json")).unwrap();
        assert_eq!(input_files(&b).unwrap(), [b.join("runs.parquet")]);
        let m = merge(&[a, b.clone()], &t.join("out")).unwrap();
        assert_eq!(m.rows, 3, "{}", m.summary());
        assert_eq!(m.gpus.len(), 1, "run.json read from the parquet's metadata");
        let back = mfx_table::read(&t.join("out/runs.parquet")).unwrap();
        let csv = mfx_table::read(&t.join("out/runs.csv")).unwrap();
        assert_eq!(back.rows, csv.rows);
        let from: serde_json::Value =
            serde_json::from_str(back.meta(MERGED_FROM_KEY).unwrap()).unwrap();
        assert_eq!(from.as_array().unwrap().len(), 2);
        assert_eq!(from[1]["run.json"]["adapter"]["name"], "H200");
        assert_eq!(
            point_keys(&t.join("out/runs.parquet")).unwrap(),
            ["k1", "k2", "k3"]
        );
        std::fs::remove_dir_all(&t).unwrap();
    }

    #[test]
    fn the_same_point_under_another_limits_profile_is_not_a_duplicate() {
        // `default` and `default --limits webgpu` on one GPU: 294 rows once dropped as duplicates.
        let t = tmp("limits");
        let hl = "schema,point_key,adapter,backend,limits,status\n";
        let a = write(&t, "a", &format!("{hl}1,k1,gpu,vulkan,adapter,ok\n"));
        let b = write(&t, "b", &format!("{hl}1,k1,gpu,vulkan,webgpu,ok\n"));
        let c = write(&t, "c", &format!("{hl}1,k1,gpu,vulkan,,ok\n"));
        let m = merge(&[a, b, c], &t.join("out")).unwrap();
        assert_eq!(m.rows, 2, "{}", m.summary());
        // An empty limits cell is the adapter's own limits (runs before the column existed).
        assert_eq!(m.duplicates.len(), 1);
        assert_eq!(m.duplicates[0].limits, "adapter");
    }

    #[test]
    fn copies_images_and_reports_the_missing_ones() {
        let t = tmp("images");
        let hi = "schema,point_key,adapter,backend,status,image_file\n";
        let a = write(&t, "a", &format!("{hi}1,k1,gpu,vulkan,ok,images/a.npy\n"));
        std::fs::create_dir_all(a.join("images")).unwrap();
        std::fs::write(a.join("images/a.npy"), b"x").unwrap();
        // b was copied without its images/ folder.
        let b = write(
            &t,
            "b",
            &format!("{hi}1,k1,cpu,gl,ok,images/b.npy\n1,k2,cpu,gl,ok,\n"),
        );
        let m = merge(&[a, b], &t.join("out")).unwrap();
        assert_eq!(m.images_copied, 1);
        assert!(t.join("out/images/a.npy").is_file());
        assert_eq!(m.images_missing, ["images/b.npy"]);
        assert!(
            m.summary()
                .contains("1 rows name an image that no input folder holds"),
            "{}",
            m.summary()
        );
    }

    #[test]
    fn refuses_mixed_schema_versions_naming_both_files() {
        let t = tmp("schema");
        let a = write(&t, "a", &format!("{H}1,k1,gpu,vulkan,ok\n"));
        let b = write(&t, "b", &format!("{H}2,k2,gpu,vulkan,ok\n"));
        let e = merge(&[a, b], &t.join("out")).unwrap_err().to_string();
        assert!(e.contains("schema version"), "{e}");
        assert!(e.contains("a/runs.csv") && e.contains("b/runs.csv"), "{e}");
        assert!(
            !t.join("out/runs.csv").exists(),
            "nothing written on refusal"
        );
    }

    #[test]
    fn refuses_different_headers_naming_the_column() {
        let t = tmp("header");
        let a = write(&t, "a", &format!("{H}1,k1,gpu,vulkan,ok\n"));
        let b = write(
            &t,
            "b",
            "schema,point_key,adapter,backend,reason\n1,k,g,v,x\n",
        );
        let e = merge(&[a, b], &t.join("out")).unwrap_err().to_string();
        assert!(
            e.contains("different CSV headers") && e.contains("'status' vs 'reason'"),
            "{e}"
        );
    }

    #[test]
    fn finds_run_folders_one_level_down_and_names_empty_inputs() {
        let t = tmp("nest");
        write(
            &t.join("job"),
            "shard-1",
            &format!("{H}1,k2,gpu,vulkan,ok\n"),
        );
        write(
            &t.join("job"),
            "shard-0",
            &format!("{H}1,k1,gpu,vulkan,ok\n"),
        );
        let files = input_files(&t.join("job")).unwrap();
        assert!(files[0].ends_with("shard-0/runs.csv") && files[1].ends_with("shard-1/runs.csv"));
        std::fs::create_dir_all(t.join("empty")).unwrap();
        let e = merge(&[t.join("empty")], &t.join("out"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("empty") && e.contains("no runs.csv"), "{e}");
    }
}
