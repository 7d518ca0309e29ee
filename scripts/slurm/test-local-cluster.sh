#!/usr/bin/env bash
# The Slurm scripts, tested for real: bring up a one-node Slurm cluster on this machine (munge +
# slurmctld + slurmd, generated config on localhost, private sockets, ports and state in a temp
# folder), submit the smoke suite as a 2-task job array with scripts/slurm/submit.sh, wait for
# the dependent merge job, and check the merged CSV holds exactly the point keys of an unsharded
# run. Everything it starts is stopped at the end.
#
#   scripts/slurm/test-local-cluster.sh        (as root; installs slurm-wlm and munge if missing)
#
# Exit 0 with "PASSED", exit 1 with "FAILED: why", or exit 0 with "SKIPPED: why" only where the
# daemons cannot be installed or started here (not root, no apt, no munge/slurm). Bounded: the
# daemons get 30 s to come up, the jobs 240 s to finish. MFX=path uses a given mfx binary.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
here="$root/scripts/slurm"
say() { echo "slurm-test: $*"; }
skip() {
    echo "slurm-test: SKIPPED: $* (the one-node Slurm test did not run)"
    exit 0
}
fail() {
    echo "slurm-test: FAILED: $*"
    for f in "${tmp:-/nonexistent}"/log/*.log "${tmp:-/nonexistent}"/out/logs/*.out; do
        [ -f "$f" ] && { echo "----- $f (last 25 lines)"; tail -n 25 "$f"; }
    done
    exit 1
}

# 1. The tools.
need=(munged slurmctld slurmd sbatch squeue scontrol)
missing() { for t in "${need[@]}"; do command -v "$t" >/dev/null || return 0; done; return 1; }
if missing; then
    [ "$(id -u)" = 0 ] || skip "slurm-wlm/munge are not installed and this is not root"
    command -v apt-get >/dev/null || skip "slurm-wlm/munge are not installed and there is no apt-get"
    say "installing slurm-wlm and munge (Debian packages)"
    export DEBIAN_FRONTEND=noninteractive
    # The install's log is kept only when the install fails (the skip names it): a fixed
    # /tmp/mfx-* file would outlive the test.
    aptlog=$(mktemp -t slurm-apt.XXXXXX.log)
    if ! timeout 600 apt-get install -y -q slurm-wlm munge >"$aptlog" 2>&1; then
        timeout 300 apt-get update -q >>"$aptlog" 2>&1
        timeout 600 apt-get install -y -q slurm-wlm munge >>"$aptlog" 2>&1 ||
            skip "apt-get install slurm-wlm munge failed (see $aptlog)"
    fi
    rm -f "$aptlog"
    missing && skip "slurm-wlm/munge installed but ${need[*]} not all on PATH"
fi
[ "$(id -u)" = 0 ] || skip "the daemons need root here (slurmd runs jobs as the submitting user)"

export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
mfx=${MFX:-}
if [ -z "$mfx" ]; then
    say "building mfx"
    (cd "$root" && cargo build -q --bin mfx) || fail "cargo build --bin mfx failed"
    mfx="$root/target/debug/mfx"
fi
"$mfx" list adapters >/dev/null 2>&1 || fail "$mfx list adapters: no adapter (run scripts/setup.sh for lavapipe)"

# 2. A private cluster in a temp folder.
tmp=$(mktemp -d /tmp/mfx-slurm.XXXXXX)
chmod 700 "$tmp"
mkdir -p "$tmp"/{munge,state,spool,log,run}
pids=()
cleanup() {
    for p in "${pids[@]}"; do
        kill "$p" 2>/dev/null
    done
    sleep 1
    for p in "${pids[@]}"; do
        kill -9 "$p" 2>/dev/null
    done
    if [ "${KEEP:-0}" = 1 ]; then say "kept $tmp"; else rm -rf "$tmp"; fi
}
trap cleanup EXIT

dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
munged --force --foreground --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/munge.sock" \
    --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/log/munged.log" --seed-file="$tmp/munge/seed" \
    >"$tmp/log/munged.stdout.log" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$tmp/munge/munge.sock" ] && break; sleep 0.2; done
[ -S "$tmp/munge/munge.sock" ] || skip "munged did not start: $(tail -n 3 "$tmp/log/munged.log" "$tmp/log/munged.stdout.log" 2>/dev/null | tr '\n' ' ')"

# Ports: two free ones above 20000 (a listening port answers a connect).
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
ctl_port=0
for _ in $(seq 50); do
    p=$((20000 + RANDOM % 30000))
    if port_free "$p" && port_free $((p + 1)); then ctl_port=$p; break; fi
done
[ "$ctl_port" != 0 ] || skip "no two free TCP ports found"
cpus=$(nproc)
node=mfxnode
conf="$tmp/slurm.conf"
cat >"$conf" <<EOF
ClusterName=mfxtest
SlurmctldHost=$(hostname -s)(127.0.0.1)
SlurmctldPort=$ctl_port
SlurmdPort=$((ctl_port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/run/slurmctld.pid
SlurmdPidFile=$tmp/run/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MinJobAge=600
GresTypes=gpu
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=1000 Gres=gpu:2 State=UNKNOWN
PartitionName=test Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
# Two stand-in "GPUs" (Slurm drops GPUs without a device file; with task/none nothing opens
# them): the array's --gres=gpu:1 is honoured and both tasks fit at once. Every task renders on
# this machine's adapter (lavapipe here).
printf 'Name=gpu File=/dev/null\nName=gpu File=/dev/zero\n' >"$tmp/gres.conf"
export SLURM_CONF=$conf

slurmctld -D -i -f "$conf" >"$tmp/log/slurmctld.stdout.log" 2>&1 &
pids+=($!)
slurmd -D -f "$conf" -N "$node" >"$tmp/log/slurmd.stdout.log" 2>&1 &
pids+=($!)
up=0
for _ in $(seq 60); do
    state=$(sinfo -h -N -n "$node" -o %t 2>/dev/null)
    case $state in idle*|mix*|alloc*) up=1; break ;; esac
    sleep 0.5
done
if [ "$up" != 1 ]; then
    echo "----- slurmctld"; tail -n 15 "$tmp/log/slurmctld.log" "$tmp/log/slurmctld.stdout.log" 2>/dev/null
    echo "----- slurmd"; tail -n 15 "$tmp/log/slurmd.log" "$tmp/log/slurmd.stdout.log" 2>/dev/null
    # A daemon that died could not start here (skip); daemons that run but disagree are a bug
    # in this script's configuration (fail).
    for p in "${pids[@]:1}"; do
        kill -0 "$p" 2>/dev/null || skip "slurmctld/slurmd exited at start-up (logs above)"
    done
    fail "slurmctld and slurmd run but node $node is not up after 30 s (state '${state:-none}')"
fi
say "cluster up: $(sinfo -h -o '%P %D %t %G' 2>/dev/null)"

# 3. The smoke suite as a 2-task array and the dependent merge, exactly as a user submits it.
out="$tmp/out"
ids=$(MFX="$mfx" SWEEP_SBATCH_ARGS="--cpus-per-task=1 --time=00:10:00" "$here/submit.sh" smoke 2 "$out") || fail "submit.sh failed"
read -r array merge <<<"$ids"
say "submitted array job $array (2 tasks) and merge job $merge (afterok:$array)"
deadline=$((SECONDS + ${JOB_TIMEOUT:-240}))
while :; do
    st=$(scontrol show job "$merge" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
    case $st in
        COMPLETED) break ;;
        FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) fail "merge job $merge ended $st" ;;
    esac
    if [ $SECONDS -gt $deadline ]; then
        squeue -o "%.12i %.9P %.10j %.9T %.10M %R" 2>&1; scontrol show job "$array" 2>&1 | head -n 40
        fail "merge job $merge not done after ${JOB_TIMEOUT:-240} s (state ${st:-unknown})"
    fi
    sleep 1
done
for t in 0 1; do
    st=$(scontrol show job "${array}_$t" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -n 1)
    [ "$st" = COMPLETED ] || fail "array task $t state '$st'"
done
say "array tasks and merge job COMPLETED"

# 4. The merged CSV equals an unsharded run's point set; each task ran its own shard.
"$mfx" sweep smoke --out "$tmp/full" --no-report >"$tmp/log/full.log" 2>&1 || fail "unsharded sweep failed"
python3 - "$out" "$tmp/full/runs.csv" <<'PY' || fail "merged point set differs (see above)"
import csv, sys
out, full = sys.argv[1], sys.argv[2]
def rows(p):
    return list(csv.DictReader(open(p)))
merged = rows(f"{out}/merged/runs.csv")
ref = rows(full)
a = sorted(r["point_key"] for r in merged)
b = sorted(r["point_key"] for r in ref)
if a != b:
    print("only merged:", sorted(set(a) - set(b)), "only unsharded:", sorted(set(b) - set(a)), "counts", len(a), len(b))
    sys.exit(1)
shards = sorted({(r["shard"], r["shards"]) for r in merged})
if shards != [("0", "2"), ("1", "2")]:
    print("shard columns", shards); sys.exit(1)
for i in (0, 1):
    s = rows(f"{out}/shard-{i}/runs.csv")
    if not s or any(r["shard"] != str(i) for r in s):
        print(f"shard-{i}/runs.csv is empty or holds rows of another shard"); sys.exit(1)
print(f"slurm-test: {len(a)} points merged from 2 shards == unsharded run")
PY
[ -f "$out/merged/report/index.html" ] || fail "the merge job wrote no report"
say "PASSED"
