#!/usr/bin/env bash
# End-to-end checks of sharding, Slurm, cross-backend comparison and the HTML report (issue 9);
# scripts/test.sh (CI) runs them after `cargo test`:
#   1. scripts/slurm/test-local-cluster.sh: a one-node Slurm cluster runs the smoke suite as a
#      2-task job array and the dependent merge; the merged CSV equals the unsharded point set.
#   2. scripts/compare-backends.sh backends: the `backends` suite with saved images on every
#      local backend (lavapipe Vulkan, llvmpipe GL), merged, reported with the comparison.
#   3. scripts/check-report.sh: that report in headless Chromium (every image loaded, the runs,
#      rows, skipped, speedup and image-agreement tables present); then a copy with one image
#      deleted must FAIL the same check (the check can fail).
#   4. `mfx report` of a committed H200 run (results/reference/2026-12-03-h200-resolve/default,
#      copied: the tree is not written) writes numbers.tex, the booktabs tables and a PDF per
#      chart, and the sample that \inputs them compiles (scripts/check-report.sh with LATEX=1).
# A step that cannot run on this machine (no Slurm daemons, no Chromium, no GL adapter) prints
# SKIPPED with the reason; anything else that goes wrong fails the script.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
cargo build -q --bin mfx
mfx=$root/target/debug/mfx
tmp=$(mktemp -d /tmp/mfx-distrib.XXXXXX)
trap 'rm -rf "$tmp"' EXIT

echo "== 1. Slurm: smoke as a 2-task job array + dependent merge"
MFX=$mfx bash scripts/slurm/test-local-cluster.sh

echo "== 2. backends suite on every local backend, merged, report"
MFX=$mfx bash scripts/compare-backends.sh backends "$tmp/cmp"
tables="runs rows notok"
if [ -d "$tmp/cmp/llvmpipe-gl" ] || [ "$(ls -d "$tmp/cmp"/*-* 2>/dev/null | wc -l)" -ge 2 ]; then
    tables="$tables speedup agreement"
    grep -q 'id="agreement"' "$tmp/cmp/merged/report/index.html" ||
        { echo "test-distrib: FAILED: no image-agreement table in the two-backend report"; exit 1; }
else
    echo "test-distrib: SKIPPED the cross-backend tables: one backend only here ($(ls "$tmp/cmp"))"
fi

echo "== 3. the report in headless Chromium"
out=$(TABLES=$tables MIN_IMAGES=5 bash scripts/check-report.sh "$tmp/cmp/merged") || { echo "$out"; exit 1; }
echo "$out"
if grep -q PASSED <<<"$out"; then
    cp -r "$tmp/cmp/merged/report" "$tmp/broken"
    victim=$(ls "$tmp/broken"/*.svg | head -n 1)
    rm "$victim"
    if TABLES=$tables bash scripts/check-report.sh "$tmp/broken" >"$tmp/broken.log" 2>&1; then
        cat "$tmp/broken.log"
        echo "test-distrib: FAILED: check-report.sh passed a report with $(basename "$victim") deleted"
        exit 1
    fi
    grep -q "$(basename "$victim")" "$tmp/broken.log" ||
        { cat "$tmp/broken.log"; echo "test-distrib: FAILED: the broken report's failure does not name $(basename "$victim")"; exit 1; }
    echo "test-distrib: check-report.sh fails a report with $(basename "$victim") deleted, as it must"
fi
echo "== 4. a committed H200 run for a paper: numbers.tex, booktabs tables, PDF charts"
h200=results/reference/2026-12-03-h200-resolve/default
mkdir -p "$tmp/h200"
cp "$h200/runs.csv" "$h200/run.json" "$tmp/h200/"
"$mfx" report "$tmp/h200" >/dev/null
out=$(LATEX=1 TABLES="runs verdict-methods rows notok" MIN_CHARTS=5 bash scripts/check-report.sh "$tmp/h200") || { echo "$out"; exit 1; }
echo "$out"
echo "test-distrib: PASSED"
