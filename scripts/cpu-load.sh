#!/usr/bin/env bash
# Runs a command under injected CPU load: N busy loops (one process each,
# never sleeping) for as long as the command runs, stopped by their pids
# afterwards. For the realtime over-budget measurement of
# docs/reliability.md §6:
#
#   scripts/cpu-load.sh 4 target/debug/pushlearn experiment push-task --mode realtime ...
set -euo pipefail

if [ $# -lt 2 ] || ! [[ "$1" =~ ^[0-9]+$ ]]; then
  echo "usage: scripts/cpu-load.sh N COMMAND [ARGS...]" >&2
  exit 2
fi
n=$1
shift
pids=()
stop() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
}
trap stop EXIT
for _ in $(seq 1 "$n"); do
  sh -c 'while :; do :; done' &
  pids+=("$!")
done
"$@"
