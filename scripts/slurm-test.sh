#!/usr/bin/env bash
# The sweep against a real Slurm (docs/sweeps.md): stands up a one-node
# cluster on 127.0.0.1 in a temporary folder — munged, slurmctld, slurmd,
# started here, not by systemd — runs the reduced ablation
# (sweeps/ablation-ci.toml) as a job array and on this machine, merges both
# and compares them byte for byte. Every daemon it started is stopped by its
# pid on exit. Where no cluster can be started it fails, saying why.
#
#   scripts/slurm-test.sh [SWEEP.toml]
#
# Needs Debian's slurmctld, slurmd, slurm-client and munge
# (`scripts/ensure-deps.sh --test` installs them) and the release binaries
# (`cargo build --release -p pushlearn-cli -p sim-plugin --bins`; PUSHLEARN_BIN
# and PUSHLEARN_SIM_BIN override where they are).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
sweep=${1:-sweeps/ablation-ci.toml}
bin=${PUSHLEARN_BIN:-${CARGO_TARGET_DIR:-$root/target}/release/pushlearn}
sim=${PUSHLEARN_SIM_BIN:-$(dirname "$bin")/pushlearn-sim}
# How long the array may take once submitted.
limit=${SLURM_TEST_LIMIT:-300}
PATH="$PATH:/usr/sbin:/sbin"

fail() { echo "slurm-test: FAILED: $*" >&2; exit 1; }
for tool in munged mungekey slurmctld slurmd sbatch squeue scancel; do
  command -v "$tool" >/dev/null 2>&1 || fail "$tool is not installed (scripts/ensure-deps.sh --test installs Debian's slurmctld, slurmd, slurm-client and munge)"
done
[ -x "$bin" ] && [ -x "$sim" ] || fail "no $bin or $sim: cargo build --release -p pushlearn-cli -p sim-plugin --bins"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/pushlearn-slurm.XXXXXX")
pids=()
cleanup() {
  status=$?
  if [ -n "${array:-}" ]; then scancel "$array" >/dev/null 2>&1 || true; fi
  # Only the daemons this script started, newest first, by pid.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill "${pids[i]}" 2>/dev/null || true
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  if [ "$status" -ne 0 ]; then
    for log in "$tmp"/*.log "$tmp"/cluster/slurm/*.log; do
      [ -f "$log" ] || continue
      echo "--- $log (last lines)" >&2
      tail -n 15 "$log" >&2
    done
  fi
  if [ -z "${KEEP:-}" ]; then rm -rf "$tmp"; else echo "slurm-test: kept $tmp" >&2; fi
}
trap cleanup EXIT
started=$(date +%s)

# Two free ports, so that two runs (or another cluster) on one machine do
# not collide.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
ss = [socket.socket() for _ in range(2)]
for s in ss: s.bind(("127.0.0.1", 0))
print(*(s.getsockname()[1] for s in ss))')
user=$(id -un)
cpus=$(nproc)
mkdir -p "$tmp"/{state,spool,munge}
chmod 700 "$tmp/munge"

# munge: a key of our own and a socket in the temporary folder.
mungekey --create --keyfile="$tmp/munge/munge.key" >/dev/null 2>&1 \
  || dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$tmp/munge/munge.key"
socket="$tmp/munge/munge.socket"
munged --foreground --force --key-file="$tmp/munge/munge.key" --socket="$socket" \
  --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/munged.log" --seed-file="$tmp/munge/munge.seed" \
  >"$tmp/munged-stderr.log" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$socket" ] && break; sleep 0.1; done
[ -S "$socket" ] || fail "munged did not create its socket $socket"

export SLURM_CONF="$tmp/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=pushlearn-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
slurmd -C >"$tmp/slurmd-C.txt" 2>&1 || fail "slurmd -C cannot read this machine: $(cat "$tmp/slurmd-C.txt")"

slurmctld -D -i -f "$SLURM_CONF" >>"$tmp/slurmctld.log" 2>&1 &
pids+=($!)
slurmd -D -N localhost -f "$SLURM_CONF" >>"$tmp/slurmd.log" 2>&1 &
pids+=($!)
# The node is up once sinfo calls it idle.
for _ in $(seq 100); do
  state=$(sinfo -h -n localhost -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null || fail "a Slurm daemon (pid $pid) exited at start"; done
  sleep 0.2
done
[ "$state" = idle ] || fail "the node did not come up within 20 s (sinfo says '${state:-nothing}')"
echo "slurm-test: one-node cluster up in $(($(date +%s) - started)) s ($cpus CPUs, ports $ctld_port/$slurmd_port)"

# The same plan two ways: as a job array, and here.
array=$("$bin" sweep slurm "$sweep" --out "$tmp/cluster" --chunk-size 2 --cpus-per-task 1 --sim-bin "$sim" --time 10)
[[ "$array" =~ ^[0-9]+$ ]] || fail "sweep slurm printed no job id: '$array'"
"$bin" sweep run "$sweep" --out "$tmp/local" --sim-bin "$sim" >/dev/null
waited=0
while [ -n "$(squeue -h -j "$array" 2>/dev/null)" ]; do
  [ "$waited" -lt "$limit" ] || fail "the array $array was still queued or running after $limit s: $(squeue -j "$array")"
  sleep 1
  waited=$((waited + 1))
done
array_done=$waited
"$bin" sweep merge "$tmp/cluster" || fail "the array's outputs do not merge"
diff -r "$tmp/local/jobs" "$tmp/cluster/jobs" || fail "the job outputs differ"
diff -r "$tmp/local/merged" "$tmp/cluster/merged" || fail "the merged results differ"
jobs=$(find "$tmp/cluster/jobs" -name '*.json' | wc -l)
# Resume: a second submission finds nothing to do and submits nothing.
again=$("$bin" sweep slurm "$sweep" --out "$tmp/cluster" --sim-bin "$sim" 2>&1)
[[ "$again" == *"nothing to submit"* ]] || fail "a resubmission of a finished sweep did not skip it: $again"
array=
echo "slurm-test: ok: $jobs jobs as a Slurm array (done $array_done s after submission) merge byte for byte into the local run's results; $(($(date +%s) - started)) s in all"
