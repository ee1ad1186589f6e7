#!/usr/bin/env bash
# The whole test suite, exactly as CI runs it: installs what is missing, then
# checks formatting and lints and runs every test of the workspace.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh --test
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --locked -- -D warnings
cargo test --workspace --locked
