#!/usr/bin/env bash
# The whole test suite, exactly as CI runs it: installs what is missing, then
# checks formatting and lints, runs every test of the workspace and checks
# that the committed quick results are current.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh --test
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --locked -- -D warnings
cargo test --workspace --locked
# The committed results still match the code: a change that moves a number
# cannot land without `pushlearn reproduce --quick` (docs/results.md).
cargo build --release --locked -p pushlearn-cli -p sim-plugin --bins
target/release/pushlearn reproduce --quick --check
target/release/pushlearn reproduce --page-only --check
