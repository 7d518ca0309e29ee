#!/usr/bin/env bash
# Runs on the GPU machine of the device tool (no Rust there): a release `mfx` built on the CPU
# machine is carried in ./.gpu, the Vulkan loader debs in ./.gl (scripts from ../shared/device),
# test meshes in ./models. Each suite's run folder is packed into $OUT/<suite>.tgz.
# Usage (as the device command): bash scripts/device/run-suites.sh SUITE [SUITE...]
# SUITE_TIMEOUT (s, default 290) bounds each suite: rows are flushed as they are measured, so a
# suite cut short still returns every finished row. Reports are drawn on the CPU machine with
# `mfx report` (REPORT=1 draws them here too).
set -u
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
export XDG_RUNTIME_DIR=/tmp
out=${OUT:-/tmp/out}
mkdir -p "$out" /tmp/r
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > /tmp/r/gpu.txt 2>&1
./.gpu/mfx list adapters >> /tmp/r/gpu.txt 2>&1
cat /tmp/r/gpu.txt
for suite in "$@"; do
  start=$(date +%s)
  extra=(--no-report)
  [ "${REPORT:-0}" = 1 ] && extra=()
  timeout "${SUITE_TIMEOUT:-290}" ./.gpu/mfx sweep "$suite" "${extra[@]}" --out "/tmp/r/$suite" > "/tmp/r/$suite.log" 2>&1
  rc=$?
  echo "suite $suite: exit $rc in $(( $(date +%s) - start )) s; $(tail -2 "/tmp/r/$suite.log" | head -1)"
  cp /tmp/r/gpu.txt "/tmp/r/$suite/gpu.txt"
  mv "/tmp/r/$suite.log" "/tmp/r/$suite/sweep.log"
  tar czf "$out/$suite.tgz" -C /tmp/r "$suite"
done
ls -la "$out"
