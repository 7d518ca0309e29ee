#!/usr/bin/env bash
# Cross-backend comparison on this machine, optionally merged with runs from other machines:
#
#   scripts/compare-backends.sh SUITE OUT [RUN_DIR…]
#
# Runs SUITE with --save-images on every backend that has an adapter here (Vulkan, then wgpu's
# GL backend; on a machine without a GPU: lavapipe and llvmpipe), merges those runs with the
# RUN_DIRs given (e.g. an H100 run made with `mfx sweep SUITE --save-images`), and builds the
# report (time per platform, speedup over BASELINE, cross-backend image agreement) into
# OUT/merged/report/index.html. BACKENDS="vulkan gl" chooses the local backends; BASELINE=NAME
# the report's baseline adapter; MFX=path the mfx binary (default: target/release/mfx).
set -euo pipefail
if [ $# -lt 2 ]; then
    sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
suite=$1 out=$2
shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
mfx=${MFX:-$root/target/release/mfx}
[ -x "$mfx" ] || (cd "$root" && cargo build --release --bin mfx)
mkdir -p "$out"
inputs=()
for b in ${BACKENDS:-vulkan gl}; do
    listing=$("$mfx" list adapters --backend "$b" 2>/dev/null || true)
    if ! grep -q '^  \[0\]' <<<"$listing"; then
        echo "compare-backends: no $b adapter here; not run"
        continue
    fi
    echo "compare-backends: $suite on $b"
    "$mfx" sweep "$suite" --backend "$b" --save-images --no-report --out "$out/$b"
    inputs+=("$out/$b")
done
inputs+=("$@")
[ "${#inputs[@]}" -gt 0 ] || { echo "compare-backends: nothing ran and no RUN_DIR given" >&2; exit 1; }
"$mfx" merge "${inputs[@]}" --out "$out/merged"
"$mfx" report "$out/merged" ${BASELINE:+--baseline "$BASELINE"}
