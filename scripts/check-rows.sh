#!/usr/bin/env bash
# The golden rows: runs the CI suites on lavapipe with the release binary and compares each
# runs.csv, restricted to its deterministic columns (scripts/rows.py says which are left out and
# why), with tests/golden/<suite>.csv. A refactoring must leave them identical; a change that
# means to change rows updates them in its own commit (`--update`) and says why.
#
#   bash scripts/check-rows.sh            # exit 1 naming every point and column that differs
#   bash scripts/check-rows.sh --update   # rewrite tests/golden/ from this build
#   MFX=path/to/mfx bash scripts/check-rows.sh   # a binary already built
#
# Measured on lavapipe (2 cores shared with other builds): smoke 1 s, aa-ci 26–111 s,
# continuum-ci 34–71 s, deferred-ci 22–36 s, geometry-ci 2–7 s, prepass-ci 12–17 s,
# shadows-ci 1–2 s, stability_ci 20–21 s, default ([software]) 116–164 s: 5–6.5 min in all.
set -euo pipefail
cd "$(dirname "$0")/.."
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}

SUITES=(smoke aa-ci continuum-ci deferred-ci geometry-ci prepass-ci shadows-ci stability_ci default)
GOLDEN=tests/golden
update=false
case "${1:-}" in
  --update) update=true ;;
  "") ;;
  *) echo "usage: $0 [--update]" >&2; exit 2 ;;
esac

if [[ -z "${MFX:-}" ]]; then
  cargo build --release --bin mfx
  MFX=target/release/mfx
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$GOLDEN"

failed=()
for s in "${SUITES[@]}"; do
  start=$SECONDS
  if ! "$MFX" sweep "$s" --out "$work/$s" --no-report --accept-failures >"$work/$s.log" 2>&1; then
    echo "== $s: the sweep failed; its log:"
    tail -20 "$work/$s.log"
    failed+=("$s")
    continue
  fi
  if $update; then
    python3 scripts/rows.py normalize "$work/$s/runs.csv" "$GOLDEN/$s.csv"
    echo "== $s: golden written ($((SECONDS - start)) s)"
  elif python3 scripts/rows.py compare "$GOLDEN/$s.csv" "$work/$s/runs.csv"; then
    echo "== $s: rows identical ($((SECONDS - start)) s)"
  else
    echo "== $s: rows differ from $GOLDEN/$s.csv (above)"
    failed+=("$s")
  fi
done
if ((${#failed[@]})); then
  echo "check-rows: ${failed[*]} differ from the golden rows (or failed to run)"
  exit 1
fi
echo "check-rows: every suite's rows match tests/golden/"
