#!/usr/bin/env bash
# The main job: set up, build, run the default suite on the best adapter (a GPU if there is one,
# otherwise lavapipe with the suite's [software] profile), and write CSV + plots.
# Usage: scripts/main.sh [suite] [extra mfx sweep args]   (default suite: default)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
cargo build --release --bin mfx
suite=${1:-default}
shift || true
./target/release/mfx list adapters
./target/release/mfx sweep "$suite" "$@"
