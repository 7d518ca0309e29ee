#!/usr/bin/env bash
# Runs on the GPU machine of the device tool (no Rust there; same set-up as run-suites.sh: a
# release `mfx` in ./.gpu, the loader debs in ./.gl). Runs the `backends` suite with saved images
# on the GPU's Vulkan adapter (and tries wgpu's GL backend, which on the H100 fails at
# request_device: its log says why), then through `--backend gles` (our own EGL GLES context),
# and packs the run folders into $OUT/backends-<NAME>.tgz.
# Merge it on the CPU machine with scripts/compare-backends.sh (see results/reference/2026-12-03-h200-backends/RUN.md).
#   bash scripts/device/backends.sh [NAME]        NAME defaults to h100
set -u
name=${1:-h100}
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
export __EGL_VENDOR_LIBRARY_FILENAMES=${__EGL_VENDOR_LIBRARY_FILENAMES:-/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json}
export XDG_RUNTIME_DIR=/tmp
out=${OUT:-/tmp/out}
r=/tmp/r/$name-vulkan
mkdir -p "$out" "$r"
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv >"$r/gpu.txt" 2>&1
./.gpu/mfx list adapters >>"$r/gpu.txt" 2>&1
./.gpu/mfx list adapters --backend gles >>"$r/gpu.txt" 2>&1
cat "$r/gpu.txt"
start=$(date +%s)
./.gpu/mfx sweep backends --save-images --out "$r" >"$r/sweep.log" 2>&1
echo "backends on vulkan: exit $? in $(($(date +%s) - start)) s; $(tail -n 1 "$r/sweep.log")"
# GL: recorded, not required (NOTES.md: the H100's GL device is lost at creation).
timeout 120 ./.gpu/mfx sweep backends --backend gl --save-images --no-report --out "/tmp/r/$name-gl" \
    >"$r/gl-attempt.log" 2>&1
echo "backends on gl: exit $? (log in $name-vulkan/gl-attempt.log): $(grep -v '^\[' "$r/gl-attempt.log" | tail -n 2 | tr '\n' ' ')"
# GLES: our own EGL GLES 3.x context (`--backend gles`, bench-core/src/gles.rs), where wgpu's own
# set-up above takes desktop GL 3.3 (no compute). Its own run folder, merged like the others.
start=$(date +%s)
timeout 300 ./.gpu/mfx sweep backends --backend gles --save-images --no-report --out "/tmp/r/$name-gles" \
    >"$r/gles.log" 2>&1
echo "backends on gles: exit $? in $(($(date +%s) - start)) s: $(grep -v '^\[' "$r/gles.log" | tail -n 2 | tr '\n' ' ')"
cp "$r/gles.log" "/tmp/r/$name-gles/sweep.log" 2>/dev/null
tar czf "$out/backends-$name.tgz" -C /tmp/r "$name-vulkan" $([ -d "/tmp/r/$name-gles" ] && echo "$name-gles")
ls -la "$out"
