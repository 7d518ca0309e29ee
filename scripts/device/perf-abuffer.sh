#!/usr/bin/env bash
# Runs on the GPU machine of the device tool, in ONE call (≤ 6 min on an H200): the speed axes of
# compute_abuffer and linked_list (scenarios/suites/perf-abuffer.toml) on the issue's scenes at
# 512², 1024² and 2048². Same set-up as run-suites.sh: no Rust there; a release `mfx` carried in
# ./.gpu (./.gpu/mfx, or gzipped as ./.gpu/mfx.gz), the Vulkan loader debs in ./.gl, and
# models/stanford-bunny.obj (a copy of ../shared/models/stanford-bunny.obj), from which the
# stacked bunnies are baked here (scripts/bake-bunny-stack.sh, awk: the 45 MB OBJ is not carried).
# Writes under $OUT: runs.csv (the sweep), runs-repeat.csv (the same suite again with the time
# left, for run-to-run spread; absent if none was left), sweep.log, gpu.txt (clocks before and
# after) and summary.txt (median ms per point, one line each; needs python3, else skipped).
# Usage (the device command): bash scripts/device/perf-abuffer.sh
# BUDGET (s, default 330) bounds both sweeps together; rows are flushed as they are measured, so
# a sweep cut short still returns every finished row.
set -u
start=$(date +%s)
budget=${BUDGET:-330}
out=${OUT:-/tmp/out}
mkdir -p "$out" /tmp/r
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
export XDG_RUNTIME_DIR=/tmp
mfx=./.gpu/mfx
if [ ! -x "$mfx" ] && [ -f ./.gpu/mfx.gz ]; then
  gunzip -c ./.gpu/mfx.gz > /tmp/mfx && chmod +x /tmp/mfx && mfx=/tmp/mfx
fi
{
  echo "before:"
  nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem,temperature.gpu --format=csv 2>&1
  "$mfx" list adapters 2>&1
} > "$out/gpu.txt"
cat "$out/gpu.txt"
if [ ! -f models/bunny-stack16.obj ]; then
  bash scripts/bake-bunny-stack.sh models/stanford-bunny.obj models/bunny-stack16.obj \
    || echo "bake failed: the bunny-stack rows will fail with 'file not found'"
fi
echo "set-up done in $(( $(date +%s) - start )) s"

sweep() { # $1 = run folder name, $2 = seconds allowed
  local s=$(date +%s)
  timeout "$2" "$mfx" sweep scenarios/suites/perf-abuffer.toml --no-report --out "/tmp/r/$1" > "/tmp/r/$1.log" 2>&1
  echo "sweep $1: exit $? in $(( $(date +%s) - s )) s; $(tail -n 1 "/tmp/r/$1.log")"
}
left=$(( budget - ($(date +%s) - start) ))
sweep main "$left"
cp /tmp/r/main/runs.csv "$out/runs.csv" 2>/dev/null
[ -f /tmp/r/main/samples.csv ] && cp /tmp/r/main/samples.csv "$out/samples.csv"
cp /tmp/r/main.log "$out/sweep.log"
left=$(( budget - ($(date +%s) - start) ))
# A repeat is worth it only if it can finish most groups (the first sweep's time, roughly).
if [ "$left" -gt $(( ($(date +%s) - start) * 2 / 3 )) ]; then
  sweep repeat "$left"
  cp /tmp/r/repeat/runs.csv "$out/runs-repeat.csv" 2>/dev/null
  cp /tmp/r/repeat.log "$out/sweep-repeat.log"
fi
{
  echo "after:"
  nvidia-smi --query-gpu=clocks.sm,clocks.mem,temperature.gpu,power.draw --format=csv 2>&1
} >> "$out/gpu.txt"
if command -v python3 >/dev/null; then
  python3 - "$out/runs.csv" > "$out/summary.txt" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
axes = ["transform", "coverage", "resolve_sort", "pool", "node", "layers"]
print(f"{'scene':34} {'res':>9} {'method':16} {'axes':52} {'ms':>8} {'x_floor':>7} {'x_blend':>7} {'frag_B':>6} status/flag")
for r in rows:
    ax = ",".join(f"{k}={r[k]}" for k in axes if r.get(k))
    res = f"{r['width']}x{r['height']}"
    xb = r.get("x_blend", "")
    fb = r.get("fragment_bytes_ratio", "")
    print(f"{r['scene_label'][:34]:34} {res:>9} {r['method']:16} {ax[:52]:52} {r.get('gpu_ms_median','')[:8]:>8} "
          f"{r.get('x_floor','')[:7]:>7} {xb[:7]:>7} {fb[:6]:>6} {r['status']} {r.get('flag','')} {r.get('reason','')[:60]}")
PY
  cat "$out/summary.txt"
fi
ls -la "$out"
echo "total $(( $(date +%s) - start )) s"
