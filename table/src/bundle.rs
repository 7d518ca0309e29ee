//! The run bundle (`mfx bundle`): one `.tar.gz` holding a run's `runs.parquet`, `run.json`,
//! samples, summary and report, for an issue or a paper's artefact. Its first entry is
//! [`MANIFEST`], which says what it holds; `mfx report` and `mfx compare` take the bundle file
//! where they take a run folder, reading it through a temporary folder ([`open`]).
//!
//! Entries are written in name order with mtime 0, mode 0644 and no owner, so one run gives one
//! byte-identical bundle.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::{err, Result, TableError};

/// The first entry of every bundle: `{"format": 1, "run": …, "files": […], …}`.
pub const MANIFEST: &str = "mfx-bundle.json";
/// The bundle format this build writes and reads.
pub const FORMAT: u64 = 1;

/// Writes `out` (a gzip-compressed tar): `manifest` as [`MANIFEST`], then each
/// `(name in the bundle, file on disk)` in name order. Written through a temporary file renamed
/// over `out`.
pub fn write(out: &Path, manifest: &serde_json::Value, files: &[(String, PathBuf)]) -> Result<()> {
    let mut files: Vec<&(String, PathBuf)> = files.iter().collect();
    files.sort_by(|a, b| a.0.cmp(&b.0));
    if let Some(w) = files.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(err(out, format!("two files named '{}'", w[0].0)));
    }
    let tmp = out.with_file_name(format!(
        ".{}.tmp",
        out.file_name().and_then(|n| n.to_str()).unwrap_or("bundle")
    ));
    let file = std::fs::File::create(&tmp).map_err(|e| err(&tmp, e))?;
    let gz = flate2::write::GzEncoder::new(file, flate2::Compression::default());
    let mut tar = tar::Builder::new(gz);
    let mut add = |name: &str, bytes: &[u8]| -> Result<()> {
        let mut h = tar::Header::new_gnu();
        h.set_size(bytes.len() as u64);
        h.set_mode(0o644);
        h.set_mtime(0);
        h.set_entry_type(tar::EntryType::Regular);
        tar.append_data(&mut h, name, bytes)
            .map_err(|e| err(out, format!("{name}: {e}")))
    };
    let json = serde_json::to_vec_pretty(manifest).map_err(|e| err(out, e))?;
    add(MANIFEST, &json)?;
    for (name, src) in files {
        let bytes = std::fs::read(src).map_err(|e| err(src, e))?;
        add(name, &bytes)?;
    }
    let gz = tar.into_inner().map_err(|e| err(out, e))?;
    gz.finish().map_err(|e| err(out, e))?;
    std::fs::rename(&tmp, out).map_err(|e| err(out, e))
}

/// Whether `path` is a bundle: a gzip file whose first tar entry is [`MANIFEST`].
pub fn is_bundle(path: &Path) -> bool {
    if !path.is_file() {
        return false;
    }
    let Ok(f) = std::fs::File::open(path) else {
        return false;
    };
    let mut archive = tar::Archive::new(flate2::read::GzDecoder::new(f));
    let Ok(mut entries) = archive.entries() else {
        return false;
    };
    matches!(
        entries.next(),
        Some(Ok(e)) if e.path().is_ok_and(|p| p == Path::new(MANIFEST))
    )
}

/// Unpacks the bundle at `path` into `dir` (created if missing) and returns its manifest. Entry
/// names that would leave `dir` (absolute, `..`) are refused by `tar`'s unpacking.
pub fn extract(path: &Path, dir: &Path) -> Result<serde_json::Value> {
    if !is_bundle(path) {
        return Err(err(
            path,
            format!("not an mfx bundle (a .tar.gz whose first entry is {MANIFEST})"),
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| err(dir, e))?;
    let f = std::fs::File::open(path).map_err(|e| err(path, e))?;
    let mut archive = tar::Archive::new(flate2::read::GzDecoder::new(f));
    for entry in archive.entries().map_err(|e| err(path, e))? {
        let mut entry = entry.map_err(|e| err(path, e))?;
        let name = entry.path().map_err(|e| err(path, e))?.into_owned();
        if !entry.unpack_in(dir).map_err(|e| err(path, e))? {
            return Err(err(
                path,
                format!("entry '{}' would leave the folder", name.display()),
            ));
        }
    }
    let mut text = String::new();
    std::fs::File::open(dir.join(MANIFEST))
        .and_then(|mut f| f.read_to_string(&mut text))
        .map_err(|e| err(path, e))?;
    let manifest: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| err(path, format!("{MANIFEST}: {e}")))?;
    match manifest.get("format").and_then(|f| f.as_u64()) {
        Some(FORMAT) => Ok(manifest),
        other => Err(TableError(format!(
            "{}: bundle format {other:?}; this mfx reads format {FORMAT}",
            path.display()
        ))),
    }
}

/// A bundle unpacked into a temporary folder, removed when dropped: a run folder to read.
pub struct Opened {
    dir: tempfile::TempDir,
    pub manifest: serde_json::Value,
}

impl Opened {
    /// The run folder (runs.parquet, run.json, samples, …).
    pub fn dir(&self) -> &Path {
        self.dir.path()
    }
}

/// Unpacks a bundle for reading.
pub fn open(path: &Path) -> Result<Opened> {
    let dir = tempfile::Builder::new()
        .prefix("mfx-bundle-")
        .tempdir()
        .map_err(|e| err(path, format!("temporary folder: {e}")))?;
    let manifest = extract(path, dir.path())?;
    Ok(Opened { dir, manifest })
}
