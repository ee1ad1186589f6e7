#!/usr/bin/env bash
# The main job: builds pushlearn and runs the thesis's Push Task Simulation on
# the embedded world — gate model, the full learning curve (1, 2, 3, 5, 10, 20,
# 30 training runs), 20 folds each, lock-step with latency emulation — and
# prints its tables beside the thesis's numbers; the figures (learning curves,
# per-position errors, end-configuration snapshots; PNG and SVG) go to
# ./results/. Extra arguments go to `pushlearn experiment push-task` (e.g.
# --model interaction, --json FILE, --plots OTHER_DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
cargo build --release --locked --workspace --bins
plots=(--plots results)
for arg in "$@"; do
    case "$arg" in --plots | --plots=*) plots=() ;; esac
done
exec target/release/pushlearn experiment push-task --model gate "${plots[@]}" "$@"
