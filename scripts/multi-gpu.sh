#!/usr/bin/env bash
# One shard per GPU of this host, in parallel, then merge + report.
#
#   scripts/multi-gpu.sh SUITE N OUT [extra mfx sweep args, e.g. --backend vulkan]
#
# Shard K of N runs on GPU K: `mfx sweep SUITE --adapter-index A_K --shard K/N`, where A_K is the
# K-th non-CPU adapter of `mfx list adapters` (set ADAPTERS="i j …" to choose the adapter indices
# yourself, e.g. ADAPTERS="0 0" to run two shards on one adapter). Each shard writes
# OUT/shard-K/runs.csv and OUT/shard-K.log; the merge goes to OUT/merged/ (runs.csv + report/).
# MFX=path/to/mfx uses a given binary (default: target/release/mfx, built if missing).
set -euo pipefail
if [ $# -lt 3 ]; then
    sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
suite=$1 n=$2 out=$3
shift 3
case $n in '' | *[!0-9]* | 0) echo "multi-gpu: N must be a positive integer, got '$n'" >&2; exit 2 ;; esac
root=$(cd "$(dirname "$0")/.." && pwd)
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
mfx=${MFX:-$root/target/release/mfx}
if [ ! -x "$mfx" ]; then
    (cd "$root" && cargo build --release --bin mfx)
fi

# The backend the shards use, so the adapter list has the same order.
backend=vulkan
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
    case ${args[i]} in
        --backend) backend=${args[i + 1]:-vulkan} ;;
        --backend=*) backend=${args[i]#--backend=} ;;
    esac
done

if [ -n "${ADAPTERS:-}" ]; then
    read -r -a adapters <<<"$ADAPTERS"
else
    # "  [3] NVIDIA H200 (vulkan, discretegpu, …)": the indices of every adapter that is not a CPU.
    mapfile -t adapters < <("$mfx" list adapters --backend "$backend" 2>/dev/null |
        sed -n 's/^  \[\([0-9]*\)\] .*(\([a-z]*\), \([a-z]*\),.*/\1 \3/p' | awk '$2 != "cpu" {print $1}')
fi
if [ "${#adapters[@]}" -lt "$n" ]; then
    echo "multi-gpu: $n shards need $n adapters, found ${#adapters[@]} GPU adapter(s) (${adapters[*]:-none}):" >&2
    "$mfx" list adapters --backend "$backend" >&2 || true
    echo "multi-gpu: set ADAPTERS=\"i j …\" to choose adapter indices (they may repeat)" >&2
    exit 1
fi

mkdir -p "$out"
pids=()
for ((k = 0; k < n; k++)); do
    a=${adapters[k]}
    echo "multi-gpu: shard $k/$n on adapter $a -> $out/shard-$k"
    "$mfx" sweep "$suite" --adapter-index "$a" --shard "$k/$n" --out "$out/shard-$k" --no-report "$@" \
        >"$out/shard-$k.log" 2>&1 &
    pids+=($!)
done
failed=0
for ((k = 0; k < n; k++)); do
    if ! wait "${pids[k]}"; then
        echo "multi-gpu: shard $k failed; last lines of $out/shard-$k.log:" >&2
        tail -n 20 "$out/shard-$k.log" >&2
        failed=1
    fi
done
if [ "$failed" != 0 ]; then
    exit 1
fi
"$mfx" merge "$out"/shard-*/ --out "$out/merged" --strict
"$mfx" report "$out/merged" ${BASELINE:+--baseline "$BASELINE"}
echo "multi-gpu: merged $n shards -> $out/merged/runs.csv"
