#!/usr/bin/env bash
# One-time set-up on a fresh machine: a Vulkan loader and, when no GPU driver is present, Mesa's
# software Vulkan driver (lavapipe) so mfx runs anywhere. Idempotent; needs root for apt-get.
set -euo pipefail
need=()
ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || need+=(libvulkan1)
# Any Vulkan ICD (NVIDIA, AMD, Intel, lavapipe) is enough; install lavapipe only when none exists.
icds=$(shopt -s nullglob; echo /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json /usr/local/nvidia/share/vulkan/icd.d/*.json)
if [ -z "$icds" ]; then
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
# The report's LaTeX check (report/tests/latex.rs, scripts/check-report.sh LATEX=1) compiles a
# sample with pdflatex and booktabs, and looks at a PDF page with pdftoppm. Optional on a
# developer's machine (those checks then say SKIPPED), required in CI (CI=true: they fail
# without it), so installed here when root.
tex=()
command -v pdflatex >/dev/null || tex+=(texlive-latex-base texlive-latex-recommended)
command -v pdftoppm >/dev/null || tex+=(poppler-utils)
if [ ${#tex[@]} -gt 0 ]; then
  if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null; then
    echo "setup: installing ${tex[*]} (the report's LaTeX and PDF check)"
    export DEBIAN_FRONTEND=noninteractive
    { apt-get install -y -qq --no-install-recommends "${tex[@]}" >/dev/null 2>&1 ||
      { apt-get update -qq && apt-get install -y -qq --no-install-recommends "${tex[@]}" >/dev/null; }; } ||
      echo "setup: could not install ${tex[*]}: the LaTeX check will fail in CI, say SKIPPED elsewhere" >&2
  else
    echo "setup: no pdflatex/pdftoppm and not root: the report's LaTeX check will say SKIPPED (Debian: apt-get install ${tex[*]})" >&2
  fi
fi
command -v cargo >/dev/null || { echo "setup: cargo not found: install Rust (https://rustup.rs)" >&2; exit 1; }
# wgpu's GL/EGL path warns without it; harmless elsewhere.
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
echo "setup: ok"
