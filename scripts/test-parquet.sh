#!/usr/bin/env bash
# runs.parquet as another tool reads it (issue 43): `mfx sweep smoke` on this machine's adapter
# (lavapipe in CI), then polars (pip, in a throw-away virtual environment) reads the run's
# runs.parquet and checks its row count against runs.csv, each typed column's dtype against the
# schema, and run.json in the file's metadata. Then `mfx dataset` of the committed reference
# runs, read back the same way. Fails on any mismatch; scripts/test.sh (CI) runs it.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
cargo build -q --bin mfx
mfx=$root/target/debug/mfx
tmp=$(mktemp -d /tmp/mfx-parquet.XXXXXX)
trap 'rm -rf "$tmp"' EXIT

"$mfx" sweep smoke --out "$tmp/run" --no-report --no-flip >"$tmp/sweep.log" 2>&1 ||
    { cat "$tmp/sweep.log"; echo "test-parquet: FAILED: the smoke sweep"; exit 1; }
"$mfx" dataset results/reference --out "$tmp/reference.parquet" >"$tmp/dataset.log" 2>&1 ||
    { cat "$tmp/dataset.log"; echo "test-parquet: FAILED: mfx dataset"; exit 1; }
python3 -m venv "$tmp/venv"
"$tmp/venv/bin/pip" install -q --disable-pip-version-check polars
"$tmp/venv/bin/python" - "$tmp/run" "$tmp/reference.parquet" <<'PY'
import csv, json, sys
import polars as pl

run, reference = sys.argv[1], sys.argv[2]
with open(f"{run}/runs.csv", newline="") as f:
    rows = list(csv.DictReader(f))
df = pl.read_parquet(f"{run}/runs.parquet")
assert df.height == len(rows), f"{df.height} rows in runs.parquet, {len(rows)} in runs.csv"
want = {
    "gpu_ms_median": pl.Float64, "samples": pl.Int64, "width": pl.Int64,
    "exact": pl.Boolean, "status": pl.String, "point_key": pl.String,
    "order_seed": pl.UInt64, "gpu_other_processes": pl.Int64,
}
for col, dtype in want.items():
    assert df.schema[col] == dtype, f"{col}: {df.schema[col]}, want {dtype}"
# The cells are the CSV's values, typed.
for r, c in zip(df.iter_rows(named=True), rows):
    assert r["point_key"] == c["point_key"]
    assert (r["samples"] is None) == (c["samples"] == ""), (r["samples"], c["samples"])
    if c["gpu_ms_median"] not in ("", "nan"):
        assert r["gpu_ms_median"] == float(c["gpu_ms_median"])
meta = pl.read_parquet_metadata(f"{run}/runs.parquet")
assert json.loads(meta["run.json"])["suite_name"] == "smoke"
types = json.loads(meta["mfx.column_types"])
assert types["status"] == "status" and types["gpu_ms_median"] == "float"
ref = pl.read_parquet(reference)
sources = json.loads(pl.read_parquet_metadata(reference)["mfx.sources"])
assert ref.height == sum(s["rows"] for s in sources) > 1000, ref.height
assert ref.schema["gpu_ms_median"] == pl.Float64 and ref.schema["schema"] == pl.Int64
print(f"test-parquet: polars {pl.__version__} read {df.height} smoke rows and "
      f"{ref.height} reference rows of {len(sources)} runs with their types")
PY
echo "test-parquet: PASSED"
