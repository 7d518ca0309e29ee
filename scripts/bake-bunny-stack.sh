#!/usr/bin/env bash
# Bakes the scene of Bevy 0.19's OIT benchmark into one OBJ: 16 stacked Stanford bunnies. Copy k
# (k = 0…15) of the bunny is normalised into [-1, 1]³ about its bounding-box centre (scale
# 2 / its largest extent), rotated 0.4·k rad about +y (x' = x cos θ + z sin θ, z' = −x sin θ +
# z cos θ, Bevy's Quat::from_rotation_y) and moved to z = −0.25·k: rotation first, then the
# move (Bevy's Transform order: translation · rotation). 16 × 69,451 = 1,111,216 triangles.
# The `obj` generator then normalises the whole stack into the unit sphere (frame_sphere camera);
# suites read it with `generator = "obj"`, `path = "models/bunny-stack16.obj"`, `alpha = 0.5`.
#
# POSIX shell + awk only (no Python, no Rust), so the device run can bake it where it runs:
#   bash scripts/bake-bunny-stack.sh [SRC] [OUT]
# SRC defaults to models/stanford-bunny.obj (else ../shared/models/stanford-bunny.obj); another
# mesh gives the same stack of it (the ogre's for the `stacked-scans` suite); OUT defaults to
# models/bunny-stack16.obj (≈ 45 MB: git-ignored, never committed; bake it, don't copy it).
# Only `v` and `f` records are read (normals are recomputed by the loader); face indices may
# carry /vt/vn suffixes, which are dropped.
set -euo pipefail
cd "$(dirname "$0")/.."
src=${1:-models/stanford-bunny.obj}
# Only the default source falls back to ../shared: a named mesh that is missing is an error.
[ $# -eq 0 ] && [ ! -f "$src" ] && src=../shared/models/stanford-bunny.obj
out=${2:-models/bunny-stack16.obj}
[ -f "$src" ] || { echo "bake-bunny-stack: no source mesh ($src)" >&2; exit 1; }
mkdir -p "$(dirname "$out")"
awk -v copies=16 -v src="$src" '
  $1 == "v" { n++; x[n] = $2 + 0; y[n] = $3 + 0; z[n] = $4 + 0; next }
  $1 == "f" {
    if (NF != 4) { printf "bake-bunny-stack: face %d is not a triangle\n", nf + 1 > "/dev/stderr"; bad = 1; exit 1 }
    nf++
    for (i = 2; i <= 4; i++) { split($i, a, "/"); f[nf, i - 1] = a[1] + 0 }
    next
  }
  END {
    if (bad) exit 1
    if (n == 0 || nf == 0) { print "bake-bunny-stack: no vertices or faces in " src > "/dev/stderr"; exit 1 }
    lx = hx = x[1]; ly = hy = y[1]; lz = hz = z[1]
    for (i = 2; i <= n; i++) {
      if (x[i] < lx) lx = x[i]; if (x[i] > hx) hx = x[i]
      if (y[i] < ly) ly = y[i]; if (y[i] > hy) hy = y[i]
      if (z[i] < lz) lz = z[i]; if (z[i] > hz) hz = z[i]
    }
    cx = (lx + hx) / 2; cy = (ly + hy) / 2; cz = (lz + hz) / 2
    ext = hx - lx; if (hy - ly > ext) ext = hy - ly; if (hz - lz > ext) ext = hz - lz
    s = 2 / ext
    printf "# %d Stanford bunnies stacked as in Bevy 0.19'"'"'s OIT benchmark (scripts/bake-bunny-stack.sh)\n", copies
    printf "# from %s: %d vertices, %d triangles per copy\n", src, n, nf
    for (k = 0; k < copies; k++) {
      t = 0.4 * k; c = cos(t); sn = sin(t)
      for (i = 1; i <= n; i++) {
        px = (x[i] - cx) * s; py = (y[i] - cy) * s; pz = (z[i] - cz) * s
        printf "v %.7g %.7g %.7g\n", px * c + pz * sn, py, -px * sn + pz * c - 0.25 * k
      }
    }
    for (k = 0; k < copies; k++) {
      o = k * n
      for (j = 1; j <= nf; j++) printf "f %d %d %d\n", f[j, 1] + o, f[j, 2] + o, f[j, 3] + o
    }
  }
' "$src" > "$out.tmp"
mv "$out.tmp" "$out"
echo "baked $out: $(grep -c '^v ' "$out") vertices, $(grep -c '^f ' "$out") triangles"
