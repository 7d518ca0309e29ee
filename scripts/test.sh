#!/usr/bin/env bash
# Every test, on whatever adapter exists (lavapipe on a machine without a GPU).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
tmp="${TMPDIR:-/tmp}"
# Anything named mfx-* made in the temp directory from here on is a test that did not clean up.
stamp="$(mktemp -t mfxteststamp.XXXXXX)"
trap 'rm -f "$stamp"' EXIT
cargo test --workspace
# The CI suites' rows against tests/golden/ (deterministic columns only): ~5 min on lavapipe.
bash scripts/check-rows.sh
# README.md is a door of at most 200 lines, and every `mfx …` line in it runs.
lines=$(wc -l <README.md)
[ "$lines" -le 200 ] || { echo "README.md has $lines lines (at most 200)" >&2; exit 1; }
bash scripts/check-readme-commands.sh
# The `default` suite under WebGPU's default limits (--limits webgpu), [software] profile: ~1 min.
bash scripts/test-limits.sh
# runs.parquet and the reference dataset read by polars (pip) with their types: ~1 min.
bash scripts/test-parquet.sh
# Sharding on a one-node Slurm cluster, the cross-backend report, the report in headless Chromium.
bash scripts/test-distrib.sh
left=$(find "$tmp" -maxdepth 1 -name 'mfx-*' -newer "$stamp" | sort)
if [ -n "$left" ]; then
  echo "tests left $(echo "$left" | wc -l) mfx-* entries in $tmp (use tempfile):" >&2
  echo "$left" >&2
  exit 1
fi
echo "temp directory clean: no mfx-* left in $tmp"
