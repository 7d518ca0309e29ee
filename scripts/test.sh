#!/usr/bin/env bash
# Every test, on whatever adapter exists (lavapipe on a machine without a GPU).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
cargo test --workspace
# The `default` suite under WebGPU's default limits (--limits webgpu), [software] profile: ~1 min.
bash scripts/test-limits.sh
# runs.parquet and the reference dataset read by polars (pip) with their types: ~1 min.
bash scripts/test-parquet.sh
# Sharding on a one-node Slurm cluster, the cross-backend report, the report in headless Chromium.
bash scripts/test-distrib.sh
