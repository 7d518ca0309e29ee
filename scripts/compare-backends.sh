#!/usr/bin/env bash
# Cross-backend comparison on this machine, optionally merged with runs from other machines:
#
#   scripts/compare-backends.sh SUITE OUT [RUN_DIR…]
#
# Runs SUITE with --save-images on every backend that has an adapter here (Vulkan, then wgpu's GL
# backend; on a machine without a GPU: lavapipe and llvmpipe) into OUT/<adapter>-<backend>/,
# merges those runs with the RUN_DIRs given (e.g. an H100 run of `mfx sweep SUITE --save-images`,
# scripts/device/backends.sh) into OUT/merged/ and builds its report (time per platform, speedup
# over BASELINE, cross-backend image agreement): OUT/merged/report/index.html.
#   BACKENDS="vulkan gl"  the local backends to run (BACKENDS="" runs none: merge RUN_DIRs only)
#   BASELINE=NAME         the report's baseline adapter (default: the first CPU adapter)
#   MFX=path              the mfx binary (default: target/release/mfx, built when missing)
# The suite should have no [software] profile (like `backends`): a point must be the same point
# (scene, resolution) on every platform to be compared.
set -euo pipefail
if [ $# -lt 2 ]; then
    sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'
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
for b in ${BACKENDS-vulkan gl}; do
    # "  [0] llvmpipe (LLVM 15.0.6, 256 bits) (vulkan, cpu, …)" -> llvmpipe
    first=$("$mfx" list adapters --backend "$b" 2>/dev/null | sed -n 's/^  \[0\] \([^ ]*\).*/\1/p' | head -n 1)
    if [ -z "$first" ]; then
        echo "compare-backends: no $b adapter here; not run"
        continue
    fi
    dir="$out/$(tr 'A-Z' 'a-z' <<<"$first" | tr -c 'a-z0-9\n' '_')-$b"
    echo "compare-backends: $suite on $b ($first) -> $dir"
    rm -rf "$dir"
    "$mfx" sweep "$suite" --backend "$b" --save-images --no-report --out "$dir" 2>&1 | grep -v 'EGL' || true
    [ -f "$dir/runs.csv" ] || { echo "compare-backends: the $b sweep wrote no runs.csv" >&2; exit 1; }
    inputs+=("$dir")
done
inputs+=("$@")
[ "${#inputs[@]}" -gt 0 ] || { echo "compare-backends: nothing ran and no RUN_DIR given" >&2; exit 1; }
rm -rf "$out/merged"
"$mfx" merge "${inputs[@]}" --out "$out/merged"
"$mfx" report "$out/merged" ${BASELINE:+--baseline "$BASELINE"}
