#!/usr/bin/env bash
# Runs on a several-GPU machine of the device tool (no Rust there; same set-up as run-suites.sh: a
# release `mfx` in ./.gpu, the loader debs in ./.gl): one shard of SUITE per GPU in parallel with
# scripts/multi-gpu.sh, the merge and report, then the same suite unsharded on GPU 0 and a check
# that both hold the same points. Packs everything into $OUT/multi-gpu-SUITE.tgz.
#   bash scripts/device/multi-gpu.sh [SUITE [N]]     defaults: default 2 (nvidia-h200-x2)
set -u
suite=${1:-default} n=${2:-2}
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
export XDG_RUNTIME_DIR=/tmp
out=${OUT:-/tmp/out}
r=/tmp/r/multi-gpu-$suite
mkdir -p "$out" "$r"
nvidia-smi --query-gpu=index,name,pci.bus_id,driver_version --format=csv >"$r/gpu.txt" 2>&1
./.gpu/mfx list adapters >>"$r/gpu.txt" 2>&1
cat "$r/gpu.txt"
start=$(date +%s)
MFX=./.gpu/mfx bash scripts/multi-gpu.sh "$suite" "$n" "$r" >"$r/multi-gpu.log" 2>&1
rc=$?
echo "multi-gpu: $n shards of $suite: exit $rc in $(($(date +%s) - start)) s"
tail -n 5 "$r/multi-gpu.log"
for ((k = 0; k < n; k++)); do echo "shard $k: $(grep -m1 'suite' "$r/shard-$k.log")"; done
start=$(date +%s)
./.gpu/mfx sweep "$suite" --adapter-index 0 --no-report --out "$r/unsharded" >"$r/unsharded.log" 2>&1
echo "unsharded on adapter 0: exit $? in $(($(date +%s) - start)) s"
python3 - "$r" <<'PY'
import csv, sys
r = sys.argv[1]
keys = lambda p: sorted(x["point_key"] for x in csv.DictReader(open(p)))
a, b = keys(f"{r}/merged/runs.csv"), keys(f"{r}/unsharded/runs.csv")
print("multi-gpu: merged shards", "==" if a == b else "!=", f"unsharded point set ({len(a)} vs {len(b)} rows)")
ad = sorted({(x["shard"], x["adapter"]) for x in csv.DictReader(open(f"{r}/merged/runs.csv"))})
print("multi-gpu: shard -> adapter:", ad)
PY
tar czf "$out/multi-gpu-$suite.tgz" -C /tmp/r "multi-gpu-$suite"
ls -la "$out"
