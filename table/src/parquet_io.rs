//! `runs.parquet`: one OPTIONAL column per CSV column, typed by `schema::cell_type` (INT64,
//! INT64 as UINT_64, DOUBLE, BOOLEAN, or UTF-8 BYTE_ARRAY for text and the typed words), zstd,
//! an empty cell as null; the key-value metadata holds `run.json` and each column's type.

use std::path::Path;
use std::sync::Arc;

use parquet::basic::{Compression, LogicalType, Repetition, Type as Physical, ZstdLevel};
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use parquet::record::Field;
use parquet::schema::types::Type;
use schema::CellType;

use crate::{err, fmt_f64, Result, Table, TableError};

/// The key-value metadata key holding the run folder's `run.json`, verbatim.
pub const RUN_JSON_KEY: &str = "run.json";
/// The key holding `{column: type}` (a `schema::CellType` name per column, as written).
pub const COLUMN_TYPES_KEY: &str = "mfx.column_types";
/// zstd's default level: Parquet's own readers and pandas decode any level.
const ZSTD_LEVEL: i32 = 3;
/// Rows per row group: a run's table is one group; a stacked dataset is cut into several.
const ROW_GROUP_ROWS: usize = 65_536;

/// What a write did beyond writing every cell typed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Written {
    /// Columns written as text although declared otherwise, because a cell did not parse as the
    /// declared type: (column, row index, cell, why). Empty for a run of this build.
    pub text_fallback: Vec<(String, usize, String, String)>,
    pub rows: usize,
}

impl Written {
    /// One line per fallen-back column, for a warning or an error.
    pub fn describe(&self) -> String {
        self.text_fallback
            .iter()
            .map(|(c, r, cell, why)| {
                format!(
                    "column '{c}' written as text: row {} cell '{cell}': {why}",
                    r + 1
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

/// The type a column is written as: its declared one where every non-empty cell parses as it,
/// else text (the first bad cell recorded); an undeclared column (an older schema's) is text.
fn column_type(table: &Table, i: usize, fallback: &mut Written) -> CellType {
    let name = &table.header[i];
    let Some(t) = schema::cell_type_of(name) else {
        return CellType::Text;
    };
    for (r, row) in table.rows.iter().enumerate() {
        let cell = row.get(i).map(String::as_str).unwrap_or("");
        if cell.is_empty() {
            continue;
        }
        if let Err(why) = t.check(cell) {
            fallback
                .text_fallback
                .push((name.clone(), r, cell.to_string(), why.to_string()));
            return CellType::Text;
        }
    }
    t
}

fn field(name: &str, t: CellType) -> parquet::errors::Result<Type> {
    let (physical, logical) = match t {
        CellType::Int => (Physical::INT64, Some(LogicalType::integer(64, true))),
        CellType::UInt => (Physical::INT64, Some(LogicalType::integer(64, false))),
        CellType::Float => (Physical::DOUBLE, None),
        CellType::Bool => (Physical::BOOLEAN, None),
        _ => (Physical::BYTE_ARRAY, Some(LogicalType::String)),
    };
    Type::primitive_type_builder(name, physical)
        .with_repetition(Repetition::OPTIONAL)
        .with_logical_type(logical)
        .build()
}

/// Writes `table` to `path` with the key-value `metadata` (plus [`COLUMN_TYPES_KEY`]).
/// Every cell must be as wide as the header; a cell that does not parse as its column's declared
/// type turns that column into text, reported in [`Written::text_fallback`] (callers that own
/// the data, like `mfx sweep`, treat that as a bug to report; a stack of old runs accepts it).
pub fn write_parquet(path: &Path, table: &Table, metadata: &[(String, String)]) -> Result<Written> {
    let pq = |e: parquet::errors::ParquetError| err(path, e);
    let width = table.header.len();
    if let Some((r, row)) = table
        .rows
        .iter()
        .enumerate()
        .find(|(_, r)| r.len() != width)
    {
        return Err(err(
            path,
            format!("row {} has {} cells for {width} columns", r + 1, row.len()),
        ));
    }
    let mut written = Written {
        rows: table.rows.len(),
        ..Default::default()
    };
    let types: Vec<CellType> = (0..width)
        .map(|i| column_type(table, i, &mut written))
        .collect();
    let fields = table
        .header
        .iter()
        .zip(&types)
        .map(|(n, t)| field(n, *t).map(Arc::new))
        .collect::<parquet::errors::Result<Vec<_>>>()
        .map_err(pq)?;
    let schema = Arc::new(
        Type::group_type_builder("mfx_runs")
            .with_fields(fields)
            .build()
            .map_err(pq)?,
    );
    let type_map: serde_json::Map<String, serde_json::Value> = table
        .header
        .iter()
        .zip(&types)
        .map(|(n, t)| (n.clone(), t.name().into()))
        .collect();
    let mut kv: Vec<KeyValue> = metadata
        .iter()
        .map(|(k, v)| KeyValue::new(k.clone(), v.clone()))
        .collect();
    kv.push(KeyValue::new(
        COLUMN_TYPES_KEY.to_string(),
        serde_json::Value::Object(type_map).to_string(),
    ));
    let props = WriterProperties::builder()
        .set_compression(Compression::ZSTD(
            ZstdLevel::try_new(ZSTD_LEVEL).map_err(pq)?,
        ))
        .set_created_by(format!("mfx {}", env!("CARGO_PKG_VERSION")))
        .set_key_value_metadata(Some(kv))
        .build();
    let file = std::fs::File::create(path).map_err(|e| err(path, e))?;
    let mut w = SerializedFileWriter::new(file, schema, Arc::new(props)).map_err(pq)?;
    let chunks: Vec<&[Vec<String>]> = if table.rows.is_empty() {
        vec![&[]]
    } else {
        table.rows.chunks(ROW_GROUP_ROWS).collect()
    };
    for rows in chunks {
        let mut rg = w.next_row_group().map_err(pq)?;
        let mut i = 0;
        while let Some(mut col) = rg.next_column().map_err(pq)? {
            let cells = || rows.iter().map(|r| r[i].as_str());
            let def: Vec<i16> = cells().map(|c| i16::from(!c.is_empty())).collect();
            let present = || cells().filter(|c| !c.is_empty());
            // Every cell was checked in `column_type`, so the parses below cannot fail.
            match types[i] {
                CellType::Int => {
                    let v: Vec<i64> = present().map(|c| c.parse().unwrap_or(0)).collect();
                    col.typed::<Int64Type>().write_batch(&v, Some(&def), None)
                }
                CellType::UInt => {
                    // UINT_64 is stored in INT64's bits (the Parquet format's rule).
                    let v: Vec<i64> = present()
                        .map(|c| c.parse::<u64>().unwrap_or(0) as i64)
                        .collect();
                    col.typed::<Int64Type>().write_batch(&v, Some(&def), None)
                }
                CellType::Float => {
                    let v: Vec<f64> = present().map(|c| c.parse().unwrap_or(f64::NAN)).collect();
                    col.typed::<DoubleType>().write_batch(&v, Some(&def), None)
                }
                CellType::Bool => {
                    let v: Vec<bool> = present().map(|c| c == "true").collect();
                    col.typed::<BoolType>().write_batch(&v, Some(&def), None)
                }
                _ => {
                    let v: Vec<ByteArray> = present().map(ByteArray::from).collect();
                    col.typed::<ByteArrayType>()
                        .write_batch(&v, Some(&def), None)
                }
            }
            .map_err(pq)?;
            col.close().map_err(pq)?;
            i += 1;
        }
        rg.close().map_err(pq)?;
    }
    w.close().map_err(pq)?;
    Ok(written)
}

/// A Parquet cell as the CSV would hold it.
fn cell_text(f: &Field) -> String {
    match f {
        Field::Null => String::new(),
        Field::Bool(b) => b.to_string(),
        Field::Long(v) => v.to_string(),
        Field::ULong(v) => v.to_string(),
        Field::Int(v) => v.to_string(),
        Field::UInt(v) => v.to_string(),
        Field::Double(v) => fmt_f64(*v),
        Field::Float(v) => fmt_f64(f64::from(*v)),
        Field::Str(s) => s.clone(),
        Field::Bytes(b) => String::from_utf8_lossy(b.data()).into_owned(),
        other => other.to_string(),
    }
}

/// Reads a Parquet file of flat columns into text cells (see the crate notes), with its
/// key-value metadata.
pub fn read_parquet(path: &Path) -> Result<Table> {
    let pq = |e: parquet::errors::ParquetError| err(path, e);
    let file = std::fs::File::open(path).map_err(|e| err(path, e))?;
    let reader = SerializedFileReader::new(file).map_err(pq)?;
    let meta = reader.metadata().file_metadata();
    let header: Vec<String> = meta
        .schema_descr()
        .columns()
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    let metadata = meta
        .key_value_metadata()
        .map(|kv| {
            kv.iter()
                .map(|k| (k.key.clone(), k.value.clone().unwrap_or_default()))
                .collect()
        })
        .unwrap_or_default();
    let mut rows = Vec::new();
    for (n, row) in reader.get_row_iter(None).map_err(pq)?.enumerate() {
        let row = row.map_err(pq)?;
        let cells: Vec<String> = row.get_column_iter().map(|(_, f)| cell_text(f)).collect();
        if cells.len() != header.len() {
            return Err(TableError(format!(
                "{}: row {} has {} cells for {} columns (nested columns are not a runs table)",
                path.display(),
                n + 1,
                cells.len(),
                header.len()
            )));
        }
        rows.push(cells);
    }
    Ok(Table {
        header,
        rows,
        metadata,
    })
}
