//! `mfx merge`: shard and machine outputs into one tidy `runs.csv`.
//!
//! Inputs are run folders (holding `runs.csv`), folders of run folders (one level down, e.g. a
//! Slurm job's `shard-*/`), or CSV files. The merge refuses inputs whose header or schema
//! version differs (naming both files), and never drops a row silently: a point seen twice
//! (same `point_key`, `adapter` and `backend`) keeps its first row in `runs.csv` and every later
//! one goes to `duplicates.csv` with the file it came from, and is listed in the summary.
//! Saved images (`images/`, from `mfx sweep --save-images`) are copied beside the merged CSV.

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
    /// File of the row that was kept, and of this later one.
    pub kept_from: PathBuf,
    pub from: PathBuf,
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
        if !self.duplicates.is_empty() {
            s.push_str(&format!(
                "\n{} duplicate points (same point_key, adapter and backend): kept the first row \
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

/// The `runs.csv` files an input names: a CSV file, a run folder, or the run folders one level
/// below it (sorted, so the merge order is stable).
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
    let direct = input.join("runs.csv");
    if direct.is_file() {
        return Ok(vec![direct]);
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir(input)
        .map_err(|e| CoreError::Io(format!("{}: {e}", input.display())))?
        .filter_map(|e| e.ok())
        .map(|e| e.path().join("runs.csv"))
        .filter(|p| p.is_file())
        .collect();
    found.sort();
    if found.is_empty() {
        return Err(CoreError::Io(format!(
            "{}: holds no runs.csv (neither directly nor in a sub-folder)",
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
    let mut tables: Vec<(PathBuf, Vec<csv::StringRecord>)> = Vec::new();
    for f in &files {
        let mut rdr = csv::Reader::from_path(f).map_err(|e| io(f, e))?;
        let h: Vec<String> = rdr
            .headers()
            .map_err(|e| io(f, e))?
            .iter()
            .map(String::from)
            .collect();
        let schema_col = h
            .iter()
            .position(|c| c == cols::SCHEMA.name)
            .ok_or_else(|| {
                CoreError::Schema(format!(
                    "{}: not an mfx runs.csv (no 'schema' column)",
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
        let mut rows = Vec::new();
        for (n, rec) in rdr.records().enumerate() {
            let rec = rec.map_err(|e| io(f, format!("row {}: {e}", n + 2)))?;
            let v = rec.get(schema_col).unwrap_or("").to_string();
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
            rows.push(rec);
        }
        tables.push((f.clone(), rows));
    }
    let (header, _) = header.expect("at least one file");
    let col = |name: &str| header.iter().position(|c| c == name);
    let (kp, ka, kb) = (
        col(cols::POINT_KEY.name),
        col(cols::ADAPTER.name),
        col(cols::BACKEND.name),
    );

    std::fs::create_dir_all(out).map_err(|e| io(out, e))?;
    let mut w = csv::Writer::from_path(&out_csv).map_err(|e| io(&out_csv, e))?;
    w.write_record(&header).map_err(|e| io(&out_csv, e))?;
    let mut seen: HashMap<(String, String, String), PathBuf> = HashMap::new();
    let mut dups: Vec<(PathBuf, csv::StringRecord, Duplicate)> = Vec::new();
    let mut rows = 0;
    let cell = |r: &csv::StringRecord, i: Option<usize>| {
        i.and_then(|i| r.get(i)).unwrap_or("").to_string()
    };
    for (f, recs) in &tables {
        for r in recs {
            let key = (cell(r, kp), cell(r, ka), cell(r, kb));
            if let Some(kept) = seen.get(&key) {
                dups.push((
                    f.clone(),
                    r.clone(),
                    Duplicate {
                        point_key: key.0,
                        adapter: key.1,
                        backend: key.2,
                        kept_from: kept.clone(),
                        from: f.clone(),
                    },
                ));
                continue;
            }
            seen.insert(key, f.clone());
            w.write_record(r).map_err(|e| io(&out_csv, e))?;
            rows += 1;
        }
    }
    w.flush().map_err(|e| io(&out_csv, e))?;
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
            rec.extend(r.iter().map(String::from));
            w.write_record(&rec).map_err(|e| io(&dup_csv, e))?;
        }
        w.flush().map_err(|e| io(&dup_csv, e))?;
    }
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
    })
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

/// The distinct point keys of a runs.csv (for shard/merge equality checks).
pub fn point_keys(csv_path: &Path) -> Result<Vec<String>> {
    let mut rdr = csv::Reader::from_path(csv_path).map_err(|e| io(csv_path, e))?;
    let h = rdr.headers().map_err(|e| io(csv_path, e))?.clone();
    let i = h
        .iter()
        .position(|c| c == cols::POINT_KEY.name)
        .ok_or_else(|| CoreError::Schema(format!("{}: no point_key column", csv_path.display())))?;
    let mut keys = Vec::new();
    for r in rdr.records() {
        keys.push(
            r.map_err(|e| io(csv_path, e))?
                .get(i)
                .unwrap_or("")
                .to_string(),
        );
    }
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

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("mfx-merge-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    const H: &str = "schema,point_key,adapter,backend,status\n";

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
