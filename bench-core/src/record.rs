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
pub use schema::{cols, Col, SCHEMA_VERSION};

use crate::{CoreError, Result};

/// One CSV row: declared column → cell text.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub cells: BTreeMap<&'static str, String>,
}

impl Row {
    pub fn new() -> Self {
        Row::default()
    }

    pub fn set(&mut self, col: Col, v: impl ToString) -> &mut Self {
        self.cells.insert(col.name, v.to_string());
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
        self.cells.insert(col.name, fmt_f64(v));
        self
    }

    pub fn get(&self, col: Col) -> Option<&str> {
        self.cells.get(col.name).map(|s| s.as_str())
    }

    /// The cell as a number, when set and numeric.
    pub fn get_f(&self, col: Col) -> Option<f64> {
        self.get(col).and_then(|s| s.parse().ok())
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
    row.set(cols::STATUS, "skipped")
        .set(cols::REASON, one_line(why));
    row
}

pub fn failed_row(mut row: Row, why: &str) -> Row {
    row.set(cols::STATUS, "failed")
        .set(cols::REASON, one_line(why));
    row
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
