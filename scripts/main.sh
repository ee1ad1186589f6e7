#!/usr/bin/env bash
# The main job: builds pushlearn and runs the thesis's Push Task Simulation on
# the embedded world — gate model, the full learning curve (1, 2, 3, 5, 10, 20,
# 30 training runs), 20 folds each, lock-step with latency emulation — and
# prints its tables beside the thesis's numbers. Extra arguments go to
# `pushlearn experiment push-task` (e.g. --model interaction, --json FILE).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
cargo build --release --locked --workspace --bins
exec target/release/pushlearn experiment push-task --model gate "$@"
