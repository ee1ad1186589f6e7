#!/usr/bin/env bash
# The main job: builds pushlearn and runs the thesis's calibration sweep on the
# embedded default world, printing its table. Extra arguments go to the sweep.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
cargo build --release --locked --workspace --bins
exec target/release/pushlearn-sim sweep "$@"
