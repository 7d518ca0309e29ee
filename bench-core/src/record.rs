//! Rows and the CSV writer: one tidy row per sweep point.
//!
//! The columns themselves are declared in the `schema` crate (shared with `report`); a row can
//! only be set through those constants, so a misspelt column does not compile. Cells of axes
//! that do not apply stay empty. Rows are flushed as they are produced.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Write;
use std::path::Path;

use scenarios::Params;
pub use schema::{cols, Col, Flag, FlagSet, GpuMsInterval, PointKey, Status, SCHEMA_VERSION};

use crate::{CoreError, Result};

/// One timed frame of a point (a row of `samples.csv`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Sum of the frame's timestamped passes (None without timestamp queries).
    pub gpu_ms: Option<f64>,
    /// Wall clock from the first encode to GPU idle.
    pub cpu_ms: f64,
    pub sm_mhz: Option<f64>,
    pub mem_mhz: Option<f64>,
    /// Dropped by the throttle rule (not in the statistics).
    pub discarded: bool,
    /// Position of the frame among all timed frames of this process: the measurement order,
    /// also when a group's points are interleaved.
    pub seq: u64,
    /// The canary's time after the frame over its baseline (None: no canary).
    pub canary_ratio: Option<f64>,
    /// Wall clock when the frame was done, ms since the Unix epoch.
    pub unix_ms: f64,
    /// The `[timing] sessions` session that took it (0 when a point has one).
    pub session: u32,
}

/// A row's FLIP comparison with the 8-bit images it was computed from, for the run's gallery of
/// worst points (`flip/worst.csv`).
#[derive(Clone, Debug)]
pub struct FlipImages {
    pub result: mfx_flip::FlipResult,
    pub method_rgb8: Vec<u8>,
    pub truth_rgb8: Vec<u8>,
    pub width: u32,
    pub height: u32,
}

/// One CSV row: declared column → cell text; and what travels with it to the sinks without
/// being a column (the point's samples for `samples.csv`, its FLIP images for the gallery).
/// The cells are private: `status` is set as a [`Status`], and `flag` only grows, through
/// [`Row::add_flag`] / [`Row::add_flags`] (a study cannot drop an earlier flag such as `noisy`).
#[derive(Clone, Debug, Default)]
pub struct Row {
    cells: BTreeMap<&'static str, String>,
    flags: FlagSet,
    pub samples: Vec<Sample>,
    pub flip: Option<Box<FlipImages>>,
}

impl Row {
    pub fn new() -> Self {
        Row::default()
    }

    /// Sets a cell. `status` and `flag` have typed setters ([`Row::set_status`],
    /// [`Row::add_flag`]); text given here for them is parsed into those (a flag is added, never
    /// replacing the ones there).
    pub fn set(&mut self, col: Col, v: impl ToString) -> &mut Self {
        let v = v.to_string();
        if col == cols::FLAG {
            let words: FlagSet = v.parse().unwrap_or_default();
            return self.add_flags(&words);
        }
        if col == cols::STATUS {
            debug_assert!(v.parse::<Status>().is_ok(), "status '{v}'");
        }
        self.cells.insert(col.name, v);
        self
    }

    pub fn set_opt<T: ToString>(&mut self, col: Col, v: Option<T>) -> &mut Self {
        if let Some(v) = v {
            self.set(col, v);
        }
        self
    }

    /// Sets a float with enough digits to round-trip.
    pub fn set_f(&mut self, col: Col, v: f64) -> &mut Self {
        self.set(col, fmt_f64(v))
    }

    /// Sets a `true`/`false` cell.
    pub fn set_bool(&mut self, col: Col, v: bool) -> &mut Self {
        self.set(col, v)
    }

    pub fn set_status(&mut self, s: Status) -> &mut Self {
        self.cells.insert(cols::STATUS.name, s.to_string());
        self
    }

    /// The row's status, when set.
    pub fn status(&self) -> Option<Status> {
        self.get(cols::STATUS).and_then(|s| s.parse().ok())
    }

    pub fn is_ok(&self) -> bool {
        self.status() == Some(Status::Ok)
    }

    pub fn get(&self, col: Col) -> Option<&str> {
        self.cells.get(col.name).map(|s| s.as_str())
    }

    /// The cell as a number, when set and numeric.
    pub fn get_f(&self, col: Col) -> Option<f64> {
        self.get(col).and_then(|s| s.parse().ok())
    }

    /// The cell as `true`/`false`, when set.
    pub fn get_bool(&self, col: Col) -> Option<bool> {
        self.get(col).and_then(|s| s.parse().ok())
    }

    /// Every set cell by column name (read-only).
    pub fn cells(&self) -> &BTreeMap<&'static str, String> {
        &self.cells
    }

    /// Adds a flag to the `flag` cell (kept `|`-joined, ordered, without repeats).
    pub fn add_flag(&mut self, flag: Flag) -> &mut Self {
        self.flags.add(flag);
        self.sync_flags()
    }

    /// Adds every flag of `flags`; a method's own word that is not a known flag is kept too
    /// (named, never dropped).
    pub fn add_flags(&mut self, flags: &FlagSet) -> &mut Self {
        self.flags.add_all(flags);
        self.sync_flags()
    }

    fn sync_flags(&mut self) -> &mut Self {
        if self.flags.is_empty() {
            self.cells.remove(cols::FLAG.name);
        } else {
            self.cells.insert(cols::FLAG.name, self.flags.to_string());
        }
        self
    }

    pub fn flags(&self) -> &FlagSet {
        &self.flags
    }

    pub fn has_flag(&self, flag: Flag) -> bool {
        self.flags.contains(flag)
    }

    /// Appends `note` to the `notes` cell (`; `-separated).
    pub fn add_note(&mut self, note: &str) -> &mut Self {
        if note.is_empty() {
            return self;
        }
        let v = match self.get(cols::NOTES) {
            Some(n) if !n.is_empty() => format!("{n}; {note}"),
            _ => note.to_string(),
        };
        self.set(cols::NOTES, v)
    }
}

pub fn fmt_f64(v: f64) -> String {
    if v.is_infinite() {
        if v > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        }
    } else if v.is_nan() {
        "nan".into()
    } else {
        format!("{v}")
    }
}

/// Reasons go in one CSV cell: one line, whitespace folded.
pub fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

pub fn skipped_row(mut row: Row, why: &str) -> Row {
    row.set_status(Status::Skipped)
        .set(cols::REASON, one_line(why));
    row
}

pub fn failed_row(mut row: Row, why: &str) -> Row {
    row.set_status(Status::Failed)
        .set(cols::REASON, one_line(why));
    row
}

/// The row of a point whose preparation or run returned `e`: `skipped` when an adapter limit
/// known before any GPU work ruled it out ([`CoreError::Limit`]), `failed` otherwise.
pub fn error_row(row: Row, e: &CoreError) -> Row {
    match e {
        CoreError::Limit(_) => skipped_row(row, &e.to_string()),
        _ => failed_row(row, &e.to_string()),
    }
}

/// Writes a point's axis values into their columns (each must be a declared column).
pub fn set_params(row: &mut Row, params: &Params) -> Result<()> {
    for (k, v) in &params.0 {
        let col = schema::by_name(k)
            .ok_or_else(|| CoreError::Schema(format!("axis '{k}' has no CSV column")))?;
        row.set(col, v);
    }
    Ok(())
}

/// Receives finished rows: the CSV writer, the progress bar, a log…
pub trait Sink {
    fn point_done(&mut self, row: &Row) -> Result<()>;
}

/// Appends rows to `runs.csv`, flushing each one so an interrupted sweep loses nothing.
pub struct CsvSink {
    file: File,
    header: Vec<&'static str>,
    pub rows_written: usize,
}

impl CsvSink {
    /// Creates `path` (truncating it) and writes the header.
    pub fn create(path: &Path) -> Result<CsvSink> {
        let header = schema::header();
        let mut file =
            File::create(path).map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&header)
            .map_err(|e| CoreError::Io(e.to_string()))?;
        file.write_all(&w.into_inner().map_err(|e| CoreError::Io(e.to_string()))?)
            .map_err(|e| CoreError::Io(e.to_string()))?;
        Ok(CsvSink {
            file,
            header,
            rows_written: 0,
        })
    }
}

impl CsvSink {
    /// Opens an existing `runs.csv` to append to (a resumed run). Its header must be this
    /// build's, or the rows would not line up: the error says which schema wrote it.
    pub fn append(path: &Path) -> Result<CsvSink> {
        let header = schema::header();
        let found = read_header(path)?;
        if found != header {
            return Err(CoreError::Schema(format!(
                "{} was written with another column set ({} columns, schema {}); this build writes schema {SCHEMA_VERSION} ({} columns): start a new run folder (or --force)",
                path.display(),
                found.len(),
                schema_of(path).unwrap_or_else(|| "?".into()),
                header.len()
            )));
        }
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
        Ok(CsvSink {
            file,
            header,
            rows_written: 0,
        })
    }
}

fn read_header(path: &Path) -> Result<Vec<String>> {
    let mut r = csv::Reader::from_path(path)
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
    Ok(r.headers()
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?
        .iter()
        .map(String::from)
        .collect())
}

/// The `schema` cell of a runs.csv's first row.
fn schema_of(path: &Path) -> Option<String> {
    let mut r = csv::Reader::from_path(path).ok()?;
    let h = r.headers().ok()?.clone();
    let i = h.iter().position(|c| c == cols::SCHEMA.name)?;
    r.records().next()?.ok()?.get(i).map(String::from)
}

/// The point keys (and the run id) of the rows a `runs.csv` holds: what a resumed run skips.
pub fn existing_points(path: &Path) -> Result<(std::collections::HashSet<String>, Option<String>)> {
    let mut r = csv::Reader::from_path(path)
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
    let h = r
        .headers()
        .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?
        .clone();
    let col = |c: Col| h.iter().position(|x| x == c.name);
    let (Some(k), run) = (col(cols::POINT_KEY), col(cols::RUN_ID)) else {
        return Err(CoreError::Schema(format!(
            "{}: no point_key column: not an mfx runs.csv",
            path.display()
        )));
    };
    let mut keys = std::collections::HashSet::new();
    let mut run_id = None;
    for rec in r.records() {
        let rec = rec.map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
        if let Some(v) = rec.get(k) {
            keys.insert(v.to_string());
        }
        if run_id.is_none() {
            run_id = run.and_then(|i| rec.get(i)).map(String::from);
        }
    }
    Ok((keys, run_id))
}

/// Cuts a line a killed process left half-written off the end of a CSV file (rows are written
/// with one `write` each, but a SIGKILL or a full disk can still split one): everything after
/// the last newline goes. Returns the bytes dropped.
pub fn drop_partial_tail(path: &Path) -> Result<u64> {
    let bytes =
        std::fs::read(path).map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
    let keep = match bytes.iter().rposition(|&b| b == b'\n') {
        Some(i) => i + 1,
        None => 0,
    };
    let dropped = (bytes.len() - keep) as u64;
    if dropped > 0 {
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
        f.set_len(keep as u64)
            .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
    }
    Ok(dropped)
}

/// Keeps only the samples of points in `keep` (a resumed run: samples of a point whose row was
/// not written would otherwise be there twice once it is measured again). Returns rows dropped.
pub fn retain_samples(path: &Path, keep: &std::collections::HashSet<String>) -> Result<usize> {
    let io = |e: csv::Error| CoreError::Io(format!("{}: {e}", path.display()));
    let mut r = csv::Reader::from_path(path).map_err(io)?;
    let h = r.headers().map_err(io)?.clone();
    let k = h
        .iter()
        .position(|c| c == schema::samples::POINT_KEY.name)
        .ok_or_else(|| CoreError::Schema(format!("{}: no point_key column", path.display())))?;
    let mut kept = Vec::new();
    let mut dropped = 0;
    for rec in r.records() {
        let rec = rec.map_err(io)?;
        if rec.get(k).is_some_and(|v| keep.contains(v)) {
            kept.push(rec);
        } else {
            dropped += 1;
        }
    }
    if dropped > 0 {
        let mut w = csv::Writer::from_path(path).map_err(io)?;
        w.write_record(&h).map_err(io)?;
        for rec in &kept {
            w.write_record(rec).map_err(io)?;
        }
        w.flush().map_err(|e| CoreError::Io(e.to_string()))?;
    }
    Ok(dropped)
}

/// Writes `samples.csv`: every timed frame of every row, long format (`schema::samples`).
pub struct SamplesSink {
    w: csv::Writer<File>,
}

impl SamplesSink {
    /// Creates `path` with its header, or appends to it (`append`: a resumed run).
    pub fn open(path: &Path, append: bool) -> Result<SamplesSink> {
        let exists = path.is_file();
        if append && exists {
            // Rows under another header (a folder an older mfx wrote) would not parse.
            let mut first = String::new();
            std::fs::File::open(path)
                .and_then(|f| {
                    std::io::BufRead::read_line(&mut std::io::BufReader::new(f), &mut first)
                })
                .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
            let want = schema::samples::ALL
                .iter()
                .map(|c| c.name)
                .collect::<Vec<_>>()
                .join(",");
            let first = first.trim_end();
            if !first.is_empty() && first != want {
                return Err(CoreError::Schema(format!(
                    "{}: its header is '{first}', this mfx writes '{want}': resume with the mfx that wrote it, or sweep into a new folder",
                    path.display()
                )));
            }
        }
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(append)
            .write(true)
            .truncate(!append)
            .open(path)
            .map_err(|e| CoreError::Io(format!("{}: {e}", path.display())))?;
        let mut w = csv::WriterBuilder::new()
            .has_headers(false)
            .from_writer(file);
        if !(append && exists) {
            w.write_record(schema::samples::ALL.iter().map(|c| c.name))
                .map_err(|e| CoreError::Io(e.to_string()))?;
        }
        Ok(SamplesSink { w })
    }
}

impl Sink for SamplesSink {
    fn point_done(&mut self, row: &Row) -> Result<()> {
        let get = |c: Col| row.get(c).unwrap_or("").to_string();
        let opt = |v: Option<f64>| v.map(fmt_f64).unwrap_or_default();
        for (i, s) in row.samples.iter().enumerate() {
            self.w
                .write_record([
                    get(cols::POINT_KEY),
                    get(cols::RUN_ID),
                    get(cols::ADAPTER),
                    i.to_string(),
                    opt(s.gpu_ms),
                    fmt_f64(s.cpu_ms),
                    opt(s.sm_mhz),
                    opt(s.mem_mhz),
                    s.discarded.to_string(),
                    s.seq.to_string(),
                    opt(s.canary_ratio),
                    format!("{:.1}", s.unix_ms),
                    s.session.to_string(),
                ])
                .map_err(|e| CoreError::Io(e.to_string()))?;
        }
        self.w.flush().map_err(|e| CoreError::Io(e.to_string()))
    }
}

/// Serialises a row in header order, refusing undeclared columns.
pub fn row_record(header: &[&'static str], row: &Row) -> Result<Vec<String>> {
    if let Some(k) = row.cells.keys().find(|k| !header.contains(k)) {
        return Err(CoreError::Schema(format!(
            "row sets undeclared column '{k}'"
        )));
    }
    Ok(header
        .iter()
        .map(|h| row.cells.get(h).cloned().unwrap_or_default())
        .collect())
}

impl Sink for CsvSink {
    fn point_done(&mut self, row: &Row) -> Result<()> {
        let rec = row_record(&self.header, row)?;
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&rec)
            .map_err(|e| CoreError::Io(e.to_string()))?;
        let bytes = w.into_inner().map_err(|e| CoreError::Io(e.to_string()))?;
        self.file
            .write_all(&bytes)
            .map_err(|e| CoreError::Io(e.to_string()))?;
        self.file
            .flush()
            .map_err(|e| CoreError::Io(e.to_string()))?;
        self.rows_written += 1;
        Ok(())
    }
}

/// Collects rows in memory (tests, the end-of-run summary).
#[derive(Default)]
pub struct VecSink(pub Vec<Row>);

impl Sink for VecSink {
    fn point_done(&mut self, row: &Row) -> Result<()> {
        row_record(&schema::header(), row)?;
        self.0.push(row.clone());
        Ok(())
    }
}

/// Whether a row's GPU time is the time of its frame (`gpu_time_trusted`): not when the
/// timestamps missed work. An untrusted row gets no `x_floor`, `x_blend` or `speedup_vs_*`.
pub fn gpu_time_trusted(row: &Row) -> bool {
    !row.has_flag(Flag::TimestampsIncomplete)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resuming_into_samples_written_under_another_header_is_refused() {
        let d_tmp = tempfile::Builder::new()
            .prefix("mfx-samples-hdr-")
            .tempdir()
            .unwrap();
        let d = d_tmp.path().to_path_buf();
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("samples.csv");
        // The header before `session` was recorded.
        std::fs::write(
            &p,
            "point_key,run_id,adapter,sample,gpu_ms\n\"k\",r,a,0,1.0\n",
        )
        .unwrap();
        let e = SamplesSink::open(&p, true)
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains("header") && e.contains("session"), "{e}");
        // A fresh file, and appending to one with this header, are fine.
        std::fs::remove_file(&p).unwrap();
        drop(SamplesSink::open(&p, true).unwrap());
        drop(SamplesSink::open(&p, true).unwrap());
        let text = std::fs::read_to_string(&p).unwrap();
        assert_eq!(text.lines().count(), 1, "one header, written once: {text}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn flags_are_ordered_and_unique_and_unknown_words_kept() {
        let mut r = Row::new();
        r.add_flag(Flag::Noisy)
            .add_flags(&format!("{}|weird", Flag::Overflow).parse().unwrap())
            .add_flag(Flag::Overflow)
            .add_flag(Flag::Hazard);
        assert_eq!(
            r.get(cols::FLAG),
            Some(format!("{}|{}|{}|weird", Flag::Overflow, Flag::Hazard, Flag::Noisy).as_str())
        );
        assert!(r.has_flag(Flag::Hazard) && !r.has_flag(Flag::Collision));
    }

    #[test]
    fn setting_the_flag_cell_adds_and_never_drops_an_earlier_flag() {
        // What studies/deferred.rs and studies/shadows once did after set_timing's `noisy`.
        let mut r = Row::new();
        r.add_flag(Flag::Noisy);
        r.set(cols::FLAG, Flag::Precision);
        assert_eq!(r.flags(), &FlagSet::of(&[Flag::Precision, Flag::Noisy]));
        assert_eq!(r.get(cols::FLAG), Some(r.flags().to_string().as_str()));
    }
}
