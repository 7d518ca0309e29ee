#!/usr/bin/env bash
# Renders every method that makes an image on one scene, plus the CPU reference, into DIR
# (default docs/gallery), and writes DIR/README.md listing them with their error.
# Usage: scripts/render-gallery.sh [DIR] [scene] [scene params...]
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-docs/gallery}
scene=${2:-shells}
params=("${@:3}")
[ ${#params[@]} -eq 0 ] && params=(count=4 segments=32)
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
cargo build --release -q --bin mfx
mkdir -p "$dir"
pargs=()
for p in "${params[@]}"; do pargs+=(--param "$p"); done
{
  echo "# Gallery: every method on ${scene}(${params[*]}) at 256×256"
  echo
  echo "Rendered by \`scripts/render-gallery.sh\` on $(./target/release/mfx list adapters | sed -n 2p | sed 's/^ *\[0\] //')."
  echo "Composited over white; the error is against the f64 CPU reference of what the method is judged against."
  echo
  echo "| method | image | error vs reference |"
  echo "|---|---|---|"
  ./target/release/mfx render --scene "$scene" "${pargs[@]}" --method depth_peel --png "$dir/depth_peel.png" --reference-png "$dir/reference.png" > /dev/null
  echo "| CPU reference (f64) | ![reference](reference.png) | — |"
  for m in $(./target/release/mfx list methods | awk '/^  [a-z]/{print $1}'); do
    case "$m" in floor_*) continue ;; esac
    if line=$(./target/release/mfx render --scene "$scene" "${pargs[@]}" --method "$m" --png "$dir/$m.png" --reference-png /tmp/gallery-ref.png 2>&1); then
      err=$(echo "$line" | grep -o 'rmse.*' || true)
      echo "| \`$m\` | ![$m]($m.png) | $err |"
    else
      echo "| \`$m\` | (not rendered: $(echo "$line" | tail -1)) | |"
    fi
  done
} > "$dir/README.md"
echo "gallery: $dir/README.md"
