//! runs.parquet round-trips every column of runs.csv with its declared type: made-up rows with
//! every type's edge cells, and every committed reference run.

use std::path::{Path, PathBuf};

use mfx_table::{read_csv, read_parquet, write_parquet, Table, COLUMN_TYPES_KEY, RUN_JSON_KEY};
use parquet::basic::{LogicalType, Type as Physical};
use parquet::file::reader::{FileReader, SerializedFileReader};
use schema::{cols, CellType, Flag, FlagSet, Status};

/// Two cells are the same value of type `t`: floats bit for bit (any NaN equals any NaN), the
/// rest as text.
fn same(t: Option<CellType>, a: &str, b: &str) -> bool {
    match t {
        Some(CellType::Float) if !a.is_empty() && !b.is_empty() => {
            let (x, y): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
            x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan())
        }
        _ => a == b,
    }
}

fn assert_round_trip(src: &str, before: &Table, after: &Table) {
    assert_eq!(before.header, after.header, "{src}: header");
    assert_eq!(before.rows.len(), after.rows.len(), "{src}: row count");
    for (r, (x, y)) in before.rows.iter().zip(&after.rows).enumerate() {
        for (i, (a, b)) in x.iter().zip(y).enumerate() {
            let name = &before.header[i];
            assert!(
                same(schema::cell_type_of(name), a, b),
                "{src}: row {} column {name}: '{a}' came back as '{b}'",
                r + 1
            );
        }
    }
}

fn physical(path: &Path) -> Vec<(String, Physical, Option<LogicalType>)> {
    let r = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    r.metadata()
        .file_metadata()
        .schema_descr()
        .columns()
        .iter()
        .map(|c| {
            (
                c.name().to_string(),
                c.physical_type(),
                c.logical_type_ref().cloned(),
            )
        })
        .collect()
}

#[test]
fn every_type_round_trips_with_its_physical_type_and_the_run_json() {
    let t = tempfile::tempdir().unwrap();
    let header: Vec<String> = [
        cols::SCHEMA,
        cols::POINT_KEY,
        cols::STATUS,
        cols::FLAG,
        cols::GPU_MS_MEDIAN,
        cols::SAMPLES,
        cols::ORDER_SEED,
        cols::EXACT,
        cols::REASON,
        cols::GPU_MS_INTERVAL,
    ]
    .iter()
    .map(|c| c.name.to_string())
    .chain(["reps".to_string()]) // a column of schema 1 only: text
    .collect();
    let flags = FlagSet::of(&[Flag::Noisy, Flag::Throttled]).to_string();
    let row = |cells: &[&str]| cells.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let table = Table {
        header,
        rows: vec![
            row(&[
                "3",
                "methods|quads(depth_complexity=8)|64x64|depth_peel|max_layers=16",
                Status::Ok.name(),
                &flags,
                "0.21761599999999998",
                "30",
                "18446744073709551615",
                "true",
                "",
                "ci95",
                "10",
            ]),
            row(&[
                "3",
                "methods|quads(depth_complexity=8)|64x64|wboit|",
                Status::Failed.name(),
                "",
                "inf",
                "-3",
                "0",
                "false",
                "out of memory, 2 GiB \"quoted\"",
                "range",
                "",
            ]),
            row(&[
                "3",
                "m|s|1x1|floor_depth|",
                Status::Skipped.name(),
                "",
                "nan",
                "",
                "",
                "",
                "",
                "",
                "",
            ]),
            row(&[
                "3",
                "m|s|1x1|floor_opaque|",
                Status::Skipped.name(),
                "",
                "-inf",
                "",
                "",
                "",
                "",
                "",
                "",
            ]),
        ],
        metadata: Vec::new(),
    };
    let p = t.path().join("runs.parquet");
    let run_json = "{\"suite_name\": \"smoke\"}".to_string();
    let w = write_parquet(&p, &table, &[(RUN_JSON_KEY.into(), run_json.clone())]).unwrap();
    assert!(w.text_fallback.is_empty(), "{}", w.describe());
    let back = read_parquet(&p).unwrap();
    assert_round_trip("made-up rows", &table, &back);
    // Canonical cells come back as the same text, nulls as empty cells.
    assert_eq!(back.rows[0][6], "18446744073709551615");
    assert_eq!(back.rows[1][4], "inf");
    assert_eq!(back.rows[2][4], "nan");
    assert_eq!(back.rows[2][5], "");
    assert_eq!(back.meta(RUN_JSON_KEY), Some(run_json.as_str()));
    let types: serde_json::Value =
        serde_json::from_str(back.meta(COLUMN_TYPES_KEY).unwrap()).unwrap();
    assert_eq!(types["flag"], "flags");
    assert_eq!(types["reps"], "text");
    let phys = physical(&p);
    let of = |n: &str| phys.iter().find(|c| c.0 == n).unwrap().clone();
    assert_eq!(of("gpu_ms_median").1, Physical::DOUBLE);
    assert_eq!(of("samples").1, Physical::INT64);
    assert_eq!(of("samples").2, Some(LogicalType::integer(64, true)));
    assert_eq!(of("order_seed").2, Some(LogicalType::integer(64, false)));
    assert_eq!(of("exact").1, Physical::BOOLEAN);
    assert_eq!(of("status").1, Physical::BYTE_ARRAY);
    assert_eq!(of("status").2, Some(LogicalType::String));
}

#[test]
fn a_cell_off_its_declared_type_turns_the_column_to_text_and_says_where() {
    let t = tempfile::tempdir().unwrap();
    let table = Table {
        header: vec!["samples".into(), "gpu_ms_median".into()],
        rows: vec![
            vec!["3".into(), "1.5".into()],
            vec!["4.5".into(), "2".into()],
        ],
        metadata: Vec::new(),
    };
    let p = t.path().join("x.parquet");
    let w = write_parquet(&p, &table, &[]).unwrap();
    assert_eq!(w.text_fallback.len(), 1);
    assert_eq!(w.text_fallback[0].0, "samples");
    assert!(
        w.describe().contains("row 2 cell '4.5'"),
        "{}",
        w.describe()
    );
    let phys = physical(&p);
    assert_eq!(phys[0].1, Physical::BYTE_ARRAY, "samples as text");
    assert_eq!(phys[1].1, Physical::DOUBLE, "the other column stays typed");
    assert_eq!(read_parquet(&p).unwrap().rows, table.rows);
    // A ragged row is an error naming it, not a shifted column.
    let bad = Table {
        rows: vec![vec!["1".into()]],
        ..table
    };
    let e = write_parquet(&p, &bad, &[]).unwrap_err().to_string();
    assert!(e.contains("row 1 has 1 cells for 2 columns"), "{e}");
}

fn reference_runs(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            reference_runs(&p, out);
        } else if p.file_name().is_some_and(|n| n == "runs.csv") {
            out.push(p);
        }
    }
}

#[test]
fn every_committed_reference_run_round_trips_typed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../results/reference");
    let mut runs = Vec::new();
    reference_runs(&root, &mut runs);
    runs.sort();
    assert!(runs.len() >= 40, "{} reference runs", runs.len());
    let t = tempfile::tempdir().unwrap();
    let p = t.path().join("runs.parquet");
    let mut typed = 0;
    for csv in &runs {
        let src = csv.strip_prefix(&root).unwrap().display().to_string();
        let before = read_csv(csv).unwrap();
        let w = write_parquet(&p, &before, &[]).unwrap();
        assert!(w.text_fallback.is_empty(), "{src}: {}", w.describe());
        let after = read_parquet(&p).unwrap();
        assert_round_trip(&src, &before, &after);
        typed += physical(&p)
            .iter()
            .filter(|c| c.1 != Physical::BYTE_ARRAY)
            .count();
    }
    assert!(typed > runs.len() * 100, "most columns typed: {typed}");
}

#[test]
fn stacked_runs_of_two_schemas_keep_every_row_under_the_union_of_columns() {
    let a = Table {
        header: vec!["schema".into(), "reps".into(), "gpu_ms_median".into()],
        rows: vec![vec!["1".into(), "10".into(), "2.5".into()]],
        metadata: Vec::new(),
    };
    let b = Table {
        header: vec!["samples".into(), "schema".into(), "gpu_ms_median".into()],
        rows: vec![
            vec!["30".into(), "3".into(), "1.5".into()],
            vec!["".into(), "3".into(), "".into()],
        ],
        metadata: Vec::new(),
    };
    let s = mfx_table::stack(&[("old".into(), a), ("new".into(), b)]);
    // run_folder first, declared columns in schema order, then schema 1's `reps`.
    assert_eq!(
        s.header,
        ["run_folder", "schema", "gpu_ms_median", "samples", "reps"]
    );
    assert_eq!(s.rows.len(), 3);
    assert_eq!(s.rows[0], ["old", "1", "2.5", "", "10"]);
    assert_eq!(s.rows[1], ["new", "3", "1.5", "30", ""]);
    let t = tempfile::tempdir().unwrap();
    let p = t.path().join("all.parquet");
    let w = write_parquet(&p, &s, &[]).unwrap();
    assert!(w.text_fallback.is_empty(), "{}", w.describe());
    assert_round_trip("stack", &s, &read_parquet(&p).unwrap());
}
