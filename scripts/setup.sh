#!/usr/bin/env bash
# One-time set-up on a fresh machine: a Vulkan loader and, when no GPU driver is present, Mesa's
# software Vulkan driver (lavapipe) so mfx runs anywhere. Idempotent; needs root for apt-get.
set -euo pipefail
need=()
ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || need+=(libvulkan1)
# Any Vulkan ICD (NVIDIA, AMD, Intel, lavapipe) is enough; install lavapipe only when none exists.
if ! ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json /usr/local/nvidia/share/vulkan/icd.d/*.json >/dev/null 2>&1; then
  need+=(mesa-vulkan-drivers)
fi
# GL backend (wgpu's `--backend gl` on Mesa llvmpipe) needs EGL.
ldconfig -p 2>/dev/null | grep -q 'libEGL.so.1' || need+=(libegl1 libgl1-mesa-dri)
if [ ${#need[@]} -gt 0 ]; then
  echo "setup: installing ${need[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: not root; install these packages yourself: ${need[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq "${need[@]}" >/dev/null
fi
command -v cargo >/dev/null || { echo "setup: cargo not found: install Rust (https://rustup.rs)" >&2; exit 1; }
# wgpu's GL/EGL path warns without it; harmless elsewhere.
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
echo "setup: ok"
