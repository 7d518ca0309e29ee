#!/usr/bin/env bash
# Submit an mfx sweep as a Slurm job array (one GPU per shard) plus a dependent merge + report.
#
#   scripts/slurm/submit.sh SUITE N OUT [extra mfx sweep args, e.g. --backend vulkan]
#
# OUT must be on a filesystem every node sees. Environment:
#   MFX           mfx binary (default: <repo>/target/release/mfx; build it first)
#   SBATCH_ARGS   extra sbatch options for both jobs, e.g. "--partition=gpu --account=proj"
#   SWEEP_SBATCH_ARGS  extra options for the array only, e.g. "--gres=gpu:h100:1 --time=00:20:00"
#   MFX_BASELINE  adapter name (substring) for the report's cross-adapter speedups
# Prints "ARRAY_JOB_ID MERGE_JOB_ID".
set -euo pipefail
if [ $# -lt 3 ]; then
    sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
suite=$1 n=$2 out=$3
shift 3
case $n in '' | *[!0-9]* | 0) echo "submit: N must be a positive integer, got '$n'" >&2; exit 2 ;; esac
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
mfx=${MFX:-$root/target/release/mfx}
[ -x "$mfx" ] || { echo "submit: $mfx is not an executable (build it: cargo build --release --bin mfx, or set MFX)" >&2; exit 1; }
mkdir -p "$out/logs"
out=$(cd "$out" && pwd)
read -r -a common <<<"${SBATCH_ARGS:-}"
read -r -a sweep_extra <<<"${SWEEP_SBATCH_ARGS:-}"
export MFX=$mfx MFX_SUITE=$suite MFX_OUT=$out MFX_SHARDS=$n MFX_SWEEP_ARGS="$*" MFX_BASELINE=${MFX_BASELINE:-}
array=$(sbatch --parsable --array="0-$((n - 1))" --chdir="$root" --export=ALL \
    --output="$out/logs/sweep-%A_%a.out" "${common[@]}" "${sweep_extra[@]}" "$here/sweep.sbatch")
array=${array%%;*}
merge=$(sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes --chdir="$root" \
    --export=ALL --output="$out/logs/merge-%j.out" "${common[@]}" "$here/merge.sbatch")
merge=${merge%%;*}
echo "$array $merge"
