#!/usr/bin/env bash
# Builds bench-core's unit-test binary in release on the CPU machine and gzips it into ./.gpu, so
# GPU-specific questions can be asked of the tests themselves on the device (no Rust there), e.g.
# whether the compute A-buffer's double-f32 vertex snapping is exact on that driver:
#   bash scripts/device/build-test-binary.sh
#   device command: for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig;
#     export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json XDG_RUNTIME_DIR=/tmp;
#     gunzip -c .gpu/bench-core-tests.gz > /tmp/t && chmod +x /tmp/t &&
#     /tmp/t compute_abuffer::tests::double_f32 compute_abuffer::tests::snaps --test-threads=1 2>&1 | tee $OUT/tests.log
#   (carry .gl and .gpu). The tests pick the first Vulkan adapter (testing::gpu). Checked here on
#   lavapipe: the three snapping tests pass from the binary (4.4 MB gzipped, built in ~2 min).
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=$(cargo test --release -p bench-core --lib --no-run --message-format=json 2>/dev/null \
  | python3 -c 'import json,sys
for l in sys.stdin:
    m=json.loads(l)
    if m.get("reason")=="compiler-artifact" and m.get("profile",{}).get("test") and m.get("executable"):
        print(m["executable"])' | tail -1)
[ -n "$bin" ] || { echo "no test binary was built" >&2; exit 1; }
mkdir -p .gpu
gzip -c "$bin" > .gpu/bench-core-tests.gz
ls -la .gpu/bench-core-tests.gz
