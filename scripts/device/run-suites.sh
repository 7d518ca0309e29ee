#!/usr/bin/env bash
# Runs on the GPU machine of the device tool (no Rust there), in one call: a release `mfx` built
# on the CPU machine is carried in ./.gpu (./.gpu/mfx, or packed as ./.gpu/mfx.gz or ./.gpu/mfx.xz), the Vulkan
# loader debs in ./.gl (../shared/device/prepare-gl.sh), and, for suites that read models,
# ./models/stanford-bunny.obj and ./models/ogre.obj (the stacks are baked here: their OBJs are not carried).
#
# Usage (as the device command): bash scripts/device/run-suites.sh JOB [JOB...]
#   JOB = SUITE or SUITE@TAG (a name or a TOML path; the run folder is SUITE or SUITE-TAG), so
#   one suite can run twice back to back (methods@a methods@b) for run-to-run spread. Extra
#   `mfx sweep` flags follow after commas: repeat-probe@pooled,--texture-memory=pooled.
# Environment:
#   BIN (default ./.gpu/mfx, also found as .gz or .xz): the mfx binary to run.
#   BUDGET (s, default 560): jobs are not started once less than MIN_LEFT (default 30) s is left,
#     and each runs with `timeout` of the time left, so the call ends within its 10 minutes;
#     rows are flushed as they are measured, so a suite cut short still returns every finished row.
#   COMPARE="A:B C:D": after the jobs, `mfx compare A B` of run folders (markdown + html kept).
#   REPORT=1 draws reports here too (they are normally drawn on the CPU machine with `mfx report`).
# Writes $OUT/runs.tgz (every run folder's tables, each with gpu.txt and sweep.log; clocks.csv sampled by
# nvidia-smi once a second over the whole call; compare-*.md) and $OUT/session.log.
# Measured with the device tool (2026-12-01): files come back only up to 16 MiB each (8 files), so
# images go in their own images-N.tgz; a machine still warm (a call within ~30 s of the last)
# keeps /tmp/r, so a follow-up call can `mfx sweep SUITE --resume --out /tmp/r/SUITE` a suite the
# budget cut short, or pack what was left behind.
set -u
start=$(date +%s)
budget=${BUDGET:-560}
min_left=${MIN_LEFT:-30}
out=${OUT:-/tmp/out}
r=/tmp/r
mkdir -p "$out" "$r"
exec > >(tee -a "$out/session.log") 2>&1
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
export XDG_RUNTIME_DIR=/tmp
# GL through EGL (`--backend gl`, `--backend gles`): NVIDIA's EGL vendor library, as in
# shared/device/prepare-gl.sh's note.
nv_egl=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
[ -f "$nv_egl" ] && export __EGL_VENDOR_LIBRARY_FILENAMES=${__EGL_VENDOR_LIBRARY_FILENAMES:-$nv_egl}
# BIN names another packed binary (e.g. .gpu/mfx-head.xz), so one call can run two builds.
bin=${BIN:-./.gpu/mfx}
bin=${bin%.xz}
bin=${bin%.gz}
mfx=$bin
unpacked=/tmp/$(basename "$bin")
if [ ! -x "$mfx" ] && [ -f "$bin.gz" ]; then
  gunzip -c "$bin.gz" > "$unpacked" && chmod +x "$unpacked" && mfx=$unpacked
fi
# xz packs the binary 30 % smaller than gzip (the tree and carry share 64 MiB); Python's lzma
# unpacks it where no xz is installed.
if [ ! -x "$mfx" ] && [ -f "$bin.xz" ]; then
  python3 -c 'import lzma,shutil,sys; shutil.copyfileobj(lzma.open(sys.argv[1]), open(sys.argv[2],"wb"))' "$bin.xz" "$unpacked" \
    && chmod +x "$unpacked" && mfx=$unpacked
fi
# The clocks over the whole call: what state each run started in, and whether it moved.
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,temperature.gpu,power.draw,clocks_throttle_reasons.active \
  --format=csv -l 1 > "$r/clocks.csv" 2>&1 &
smi=$!
{
  nvidia-smi --query-gpu=name,pci.bus_id,driver_version,clocks.sm,clocks.max.sm,clocks.mem,temperature.gpu --format=csv 2>&1
  "$mfx" --version 2>&1
  "$mfx" list adapters 2>&1
  "$mfx" list adapters --backend gles 2>&1
} > "$r/gpu.txt"
cat "$r/gpu.txt"
need_bunny=0
need_ogre=0
for job in "$@"; do
  job=${job%%,*}
  case "${job%@*}" in perf-abuffer* | perf-binned* | exp-binned* | *bunny* | stacked-scans* | perf-issue41* | views | views,*) need_bunny=1 ;; esac
  case "${job%@*}" in stacked-scans* | perf-issue41*) need_ogre=1 ;; esac
done
if [ "$need_bunny" = 1 ] && [ ! -f models/bunny-stack16.obj ]; then
  bash scripts/bake-bunny-stack.sh models/stanford-bunny.obj models/bunny-stack16.obj \
    || echo "bake failed: the bunny-stack rows will fail with 'file not found'"
fi
# The second stacked scan (issue 34 goal 4): 16 ogres, baked the same way from models/ogre.obj.
if [ "$need_ogre" = 1 ] && [ ! -f models/ogre-stack16.obj ]; then
  bash scripts/bake-bunny-stack.sh models/ogre.obj models/ogre-stack16.obj \
    || echo "bake failed: the ogre-stack rows will fail with 'file not found'"
fi
echo "set-up done in $(( $(date +%s) - start )) s"
for spec in "$@"; do
  job=${spec%%,*}
  flags=()
  [ "$spec" != "$job" ] && IFS=, read -r -a flags <<< "${spec#*,}"
  suite=${job%@*}
  name=$(basename "$suite" .toml)
  [ "$job" != "$suite" ] && name="$name-${job#*@}"
  left=$(( budget - ($(date +%s) - start) ))
  if [ "$left" -lt "$min_left" ]; then
    echo "job $job: not started ($left s left of the budget)"
    continue
  fi
  s=$(date +%s)
  extra=(--no-report)
  [ "${REPORT:-0}" = 1 ] && extra=()
  timeout "$left" "$mfx" sweep "$suite" "${extra[@]}" "${flags[@]}" --out "$r/$name" > "$r/$name.log" 2>&1
  rc=$?
  echo "job $job: exit $rc in $(( $(date +%s) - s )) s; $(grep -m1 -E '^mfx: .* rows' "$r/$name.log" | tail -c 200)"
  mkdir -p "$r/$name"
  cp "$r/gpu.txt" "$r/$name/gpu.txt"
  mv "$r/$name.log" "$r/$name/sweep.log"
done
for pair in ${COMPARE:-}; do
  a=${pair%%:*}
  b=${pair#*:}
  if [ -f "$r/$a/runs.csv" ] && [ -f "$r/$b/runs.csv" ]; then
    "$mfx" compare "$r/$a" "$r/$b" --html "$r/compare-$a-$b" > "$r/compare-$a-$b.md" 2> "$r/compare-$a-$b.log"
    echo "compare $a $b: exit $?; $(grep -m1 'points compared' "$r/compare-$a-$b.md")"
  fi
done
kill "$smi" 2>/dev/null
nvidia-smi --query-gpu=clocks.sm,clocks.mem,temperature.gpu,power.draw --format=csv >> "$r/gpu.txt" 2>&1
# The device tool brings back files of at most 16 MiB: the tables and logs in runs.tgz (small),
# images (flip/ and --save-images PNGs) and runs.json in one images-N.tgz per run folder, each
# left out with a line in session.log when it is still too large.
tar czf "$out/runs.tgz" -C "$r" --exclude='*.png' --exclude='runs.json' .
n=0
for d in "$r"/*/; do
  name=$(basename "$d")
  # A folder without images takes none of the 8 files a call brings back.
  [ -n "$(cd "$r" && find "$name" -name '*.png' -print -quit)" ] || continue
  n=$((n + 1))
  (cd "$r" && find "$name" \( -name '*.png' -o -name runs.json \) -print0 | tar czf "$out/images-$n.tgz" --null -T -)
  size=$(stat -c %s "$out/images-$n.tgz")
  if [ "$size" -gt 16000000 ] || [ "$n" -gt 6 ]; then
    echo "images of $name: $size B, not brought back (16 MiB a file, 8 files a call)"
    rm -f "$out/images-$n.tgz"
  else
    echo "images of $name: images-$n.tgz ($size B)"
  fi
done
echo "done in $(( $(date +%s) - start )) s"
ls -la "$out"
