#!/usr/bin/env bash
# Runs every `mfx …` command line of README.md (in its ```sh blocks; `cargo run --release --bin
# mfx --` counts as `mfx`), as a new user would type it, and fails on a non-zero exit or an
# "error:" on stderr. Sweeps run with --dry-run (the points, nothing measured); every other line
# runs for real in a scratch folder whose run folders (results/a, results/b, results/mine, r0…r3
# and cal.json) come from one small smoke run, so `report`, `compare`, `merge` and friends
# have something to read. Renders are cut to 32×32 unless the line sets a size.
# Usage: bash scripts/check-readme-commands.sh [README.md]   (builds target/debug/mfx if needed)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
readme="$(realpath "${1:-$root/README.md}")"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
(cd "$root" && cargo build -q --bin mfx)
mfx="$root/target/debug/mfx"

work="$(mktemp -d -t mfxreadme.XXXXXX)"
trap 'rm -rf "$work"' EXIT
# The scratch folder looks like the repository to the relative paths a README line uses.
for p in scenarios models scripts; do
  [ -e "$root/$p" ] && ln -s "$root/$p" "$work/$p"
done
mkdir -p "$work/results"
ln -s "$root/results/reference" "$work/results/reference"
cd "$work"

# Fixtures: one smoke run on this machine's adapter, copied to every run folder a line may name.
"$mfx" sweep smoke --out results/a >"$work/fixture.log" 2>&1 || {
  cat "$work/fixture.log"
  echo "check-readme-commands: the fixture smoke run failed" >&2
  exit 1
}
for d in results/b results/mine r0 r1 r2 r3; do
  mkdir -p "$d" && cp -r results/a/. "$d/"
done
"$mfx" calibrate results/a results/b --out cal.json >/dev/null 2>&1 || true

python3 - "$readme" >"$work/commands.txt" <<'PY'
import re, shlex, sys
text = open(sys.argv[1]).read()
lines, block = [], False
buf = ""
for raw in text.splitlines():
    if raw.startswith("```"):
        block = raw.strip() in ("```sh", "```bash", "```shell") if not block else False
        continue
    if not block:
        continue
    line = buf + raw.strip()
    if line.endswith("\\"):
        buf = line[:-1] + " "
        continue
    buf = ""
    line = re.sub(r"^cargo run --release --bin mfx --\s*", "mfx ", line)
    if not line.startswith("mfx "):
        continue
    # Drop a trailing comment (a '#' after two spaces or at a word start, outside quotes).
    words = shlex.split(line, comments=True)
    print("\x1f".join(words[1:]))
PY

n=0
failed=0
while IFS= read -r cmd; do
  IFS=$'\x1f' read -r -a args <<<"$cmd"
  case "${args[0]}" in
    sweep)
      [[ " ${args[*]} " == *" --dry-run "* ]] || args+=(--dry-run)
      ;;
    render)
      [[ " ${args[*]} " == *" --width "* || " ${args[*]} " == *" --camera-in "* ]] || args+=(--width 32 --height 32)
      ;;
  esac
  n=$((n + 1))
  set +e
  "$mfx" "${args[@]}" >"$work/out.txt" 2>"$work/err.txt"
  rc=$?
  set -e
  if [[ $rc -ne 0 ]] || grep -q "error:" "$work/err.txt"; then
    failed=$((failed + 1))
    echo "FAILED (exit $rc): mfx ${args[*]}"
    sed 's/^/    /' "$work/err.txt" | tail -n 15
  else
    echo "ok: mfx ${args[*]}"
  fi
done <"$work/commands.txt"
if [[ $n -eq 0 ]]; then
  echo "check-readme-commands: no mfx command line found in $readme" >&2
  exit 1
fi
echo "README commands: $((n - failed)) passed, $failed failed"
[[ $failed -eq 0 ]]
