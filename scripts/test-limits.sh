#!/usr/bin/env bash
# The `default` suite under WebGPU's default limits (`--limits webgpu`) on this machine's adapter
# (lavapipe in CI, its [software] profile: ~1 min): every row carries the profile, nothing
# fails, what does not fit is a skipped row naming the limit, and the report has its
# "Fits a browser?" table. Splitting itself is tested in studies/multifragment/tests/limits.rs (a lowered
# binding limit on small scenes, judged against the f64 reference).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
cargo build -q --bin mfx
mfx=$root/target/debug/mfx
tmp=$(mktemp -d /tmp/mfx-limits.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
"$mfx" sweep default --limits webgpu --out "$tmp/web" --no-flip
python3 - "$tmp/web" <<'PY'
import csv, json, sys
d = sys.argv[1]
rows = list(csv.DictReader(open(f"{d}/runs.csv")))
bad = [r for r in rows if r["limits"] != "webgpu"]
assert not bad, f"{len(bad)} rows without limits = webgpu"
failed = [(r["method"], r["reason"]) for r in rows if r["status"] == "failed"]
assert not failed, f"failed rows under --limits webgpu: {failed[:5]}"
skipped = [r for r in rows if r["status"] == "skipped"]
for r in skipped:
    assert r["reason"], f"{r['method']}: skipped without a reason"
# Rows the profile ruled out name it (WebGPU's limit or the `webgpu` profile's features).
limited = [r for r in skipped if "WebGPU" in r["reason"] or "`webgpu`" in r["reason"]]
assert limited, "no row skipped naming WebGPU's limits"
assert json.load(open(f"{d}/run.json"))["limits"] == "webgpu", "run.json lacks limits = webgpu"
ok = sum(r["status"] == "ok" for r in rows)
split = sum(bool(r["split"]) for r in rows)
print(f"test-limits: {len(rows)} rows: {ok} ok ({split} split), {len(skipped)} skipped ({len(limited)} by WebGPU's limits)")
for m in sorted({(r['method'], r['reason'][:140]) for r in limited}):
    print("  skipped:", *m)
PY
grep -q "Fits a browser" "$tmp/web/report/index.html" ||
    { echo "test-limits: FAILED: no 'Fits a browser?' table in the report"; exit 1; }
echo "test-limits: PASSED"
