//! A run's rows as a table, from `runs.csv` or `runs.parquet` alike, and `runs.parquet` written
//! typed from the schema (`schema::cell_type`): what `mfx merge`, `mfx compare`, `mfx report`
//! and `mfx dataset` read, and what pandas, polars or DuckDB read with types.
//!
//! Cells travel as text (the CSV's), so a reader of either file sees the same table: a Parquet
//! cell is printed back as the CSV would hold it (floats with Rust's shortest round-trip digits,
//! `inf`/`-inf`/`nan`, `true`/`false`, a null as an empty cell).

pub mod bundle;
mod parquet_io;

use std::path::{Path, PathBuf};

pub use parquet_io::{read_parquet, write_parquet, Written, COLUMN_TYPES_KEY, RUN_JSON_KEY};

/// File names inside a run folder.
pub const RUNS_CSV: &str = "runs.csv";
pub const RUNS_PARQUET: &str = "runs.parquet";

/// An error naming the file (and row, column, value where one is at fault).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct TableError(pub String);

pub type Result<T> = std::result::Result<T, TableError>;

pub(crate) fn err(path: &Path, e: impl std::fmt::Display) -> TableError {
    TableError(format!("{}: {e}", path.display()))
}

/// Rows as text cells under a header, with the file's key-value metadata (Parquet only).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    pub header: Vec<String>,
    /// Each row has one cell per header column.
    pub rows: Vec<Vec<String>>,
    /// Key-value metadata of a Parquet file (`run.json`, `mfx.column_types`, …); empty for CSV.
    pub metadata: Vec<(String, String)>,
}

impl Table {
    /// The index of the column called `name`.
    pub fn col(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// A metadata value by key.
    pub fn meta(&self, key: &str) -> Option<&str> {
        self.metadata
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// A float as the CSV writes it: Rust's shortest round-trip digits, `inf`, `-inf`, `nan`.
pub fn fmt_f64(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v}")
    }
}

/// Reads a CSV file (header first; every row must have the header's width).
pub fn read_csv(path: &Path) -> Result<Table> {
    let mut rdr = csv::Reader::from_path(path).map_err(|e| err(path, e))?;
    let header: Vec<String> = rdr
        .headers()
        .map_err(|e| err(path, e))?
        .iter()
        .map(String::from)
        .collect();
    let mut rows = Vec::new();
    for (n, rec) in rdr.records().enumerate() {
        let rec = rec.map_err(|e| err(path, format!("row {}: {e}", n + 2)))?;
        rows.push(rec.iter().map(String::from).collect());
    }
    Ok(Table {
        header,
        rows,
        metadata: Vec::new(),
    })
}

/// Whether `path` is a Parquet file: its name ends in `.parquet`, or it starts with `PAR1`.
pub fn is_parquet(path: &Path) -> bool {
    if path.extension().is_some_and(|e| e == "parquet") {
        return true;
    }
    let mut magic = [0u8; 4];
    std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut magic))
        .is_ok()
        && &magic == b"PAR1"
}

/// Reads a runs table: a Parquet file ([`is_parquet`]) or a CSV file.
pub fn read(path: &Path) -> Result<Table> {
    if is_parquet(path) {
        read_parquet(path)
    } else {
        read_csv(path)
    }
}

/// The runs table a run folder holds: `runs.csv` where it is (the file written row by row, the
/// source of truth while a run is in flight), else `runs.parquet`; `None` if neither.
pub fn in_folder(dir: &Path) -> Option<PathBuf> {
    [RUNS_CSV, RUNS_PARQUET]
        .into_iter()
        .map(|n| dir.join(n))
        .find(|p| p.is_file())
}

/// The runs table a path names: a file itself, or the table of a run folder ([`in_folder`]).
pub fn locate(path: &Path) -> Result<PathBuf> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    if !path.is_dir() {
        return Err(err(path, "no such file or folder"));
    }
    in_folder(path).ok_or_else(|| err(path, format!("holds neither {RUNS_CSV} nor {RUNS_PARQUET}")))
}

/// Writes a table as CSV (header, then the rows).
pub fn write_csv(path: &Path, table: &Table) -> Result<()> {
    let mut w = csv::Writer::from_path(path).map_err(|e| err(path, e))?;
    w.write_record(&table.header).map_err(|e| err(path, e))?;
    for r in &table.rows {
        w.write_record(r).map_err(|e| err(path, e))?;
    }
    w.flush().map_err(|e| err(path, e))
}

/// Writes `dir/runs.parquet` from `dir/runs.csv`, with `dir/run.json` (where there is one) in its
/// key-value metadata. Written through a temporary file renamed over the old one, so a reader
/// never sees half a file.
pub fn write_runs_parquet(dir: &Path) -> Result<Written> {
    let table = read_csv(&dir.join(RUNS_CSV))?;
    let mut meta = Vec::new();
    if let Ok(run) = std::fs::read_to_string(dir.join("run.json")) {
        meta.push((RUN_JSON_KEY.to_string(), run));
    }
    let tmp = dir.join(format!(".{RUNS_PARQUET}.tmp"));
    let written = write_parquet(&tmp, &table, &meta)?;
    let path = dir.join(RUNS_PARQUET);
    std::fs::rename(&tmp, &path).map_err(|e| err(&path, e))?;
    Ok(written)
}

/// The column [`stack`] adds: where each row came from.
pub const RUN_FOLDER: &str = "run_folder";

/// Stacks tables (each named by its run folder) into one for history queries: the declared
/// columns any of them has in schema order, then older columns no longer declared (sorted), after
/// [`RUN_FOLDER`]; a column a table lacks is empty in its rows. Rows keep their order.
pub fn stack(tables: &[(String, Table)]) -> Table {
    let mut undeclared: Vec<String> = Vec::new();
    let mut declared: std::collections::HashSet<&str> = std::collections::HashSet::new();
    for (_, t) in tables {
        for h in &t.header {
            match schema::by_name(h) {
                Some(c) => {
                    declared.insert(c.name);
                }
                None if h != RUN_FOLDER && !undeclared.contains(h) => undeclared.push(h.clone()),
                None => {}
            }
        }
    }
    undeclared.sort();
    let header: Vec<String> = std::iter::once(RUN_FOLDER.to_string())
        .chain(
            schema::all()
                .filter(|c| declared.contains(c.name))
                .map(|c| c.name.to_string()),
        )
        .chain(undeclared)
        .collect();
    let mut rows = Vec::new();
    for (folder, t) in tables {
        let at: Vec<Option<usize>> = header.iter().map(|h| t.col(h)).collect();
        for r in &t.rows {
            let mut row: Vec<String> = at
                .iter()
                .map(|i| i.and_then(|i| r.get(i)).cloned().unwrap_or_default())
                .collect();
            row[0] = folder.clone();
            rows.push(row);
        }
    }
    Table {
        header,
        rows,
        metadata: Vec::new(),
    }
}
