#!/usr/bin/env bash
# The whole test suite, exactly as CI runs it: installs what is missing, then
# checks formatting and lints, runs every test of the workspace, checks
# that the committed quick results are current, runs a sweep on a real
# one-node Slurm, and builds, lints and tests the Python package, and the
# wheel that installs without Rust.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh --test
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --locked -- -D warnings
# The learner daemon alone (no experiments, figures or viewer) still builds.
cargo clippy -p pushlearn-cli --no-default-features --all-targets --locked -- -D warnings
# The world daemon without MuJoCo (sim-plugin's default feature `mujoco`
# off) still builds: it links libode alone (docs/world.md, "Two engines").
cargo build -p sim-plugin --no-default-features --locked
cargo test --workspace --locked
# The committed results still match the code: a change that moves a number
# cannot land without `pushlearn reproduce --quick` (docs/results.md).
cargo build --release --locked -p pushlearn-cli -p sim-plugin --bins
target/release/pushlearn reproduce --quick --check
# The same documents from worlds spawned as daemons: the embedded worlds the
# reproduction uses by default step the daemon's physics bit for bit.
target/release/pushlearn reproduce --quick --check --world spawn
target/release/pushlearn reproduce --page-only --check
# Sweeps on a real Slurm: a one-node cluster started (and stopped) by the
# script, the reduced ablation as a job array, merged, byte-identical to the
# same plan run here (docs/sweeps.md). Fails, saying why, without a cluster.
PUSHLEARN_BIN="$PWD/target/release/pushlearn" scripts/slurm-test.sh
# The Python package (python/): installed into .venv exactly as the README
# says (`pip install .`, maturin building the native part), then linted,
# type-checked and tested against the binaries just built.
# (maturin's build hook runs `maturin` from PATH: the venv's. The package's
# backend first runs the cargo build of the release binaries above, which
# then builds nothing, and puts the binaries into the package.)
PATH="$PWD/.venv/bin:$PATH" .venv/bin/python -m pip install --quiet --no-build-isolation .
.venv/bin/ruff format --check python examples/python build_backend
.venv/bin/ruff check python examples/python build_backend
(cd python && MYPYPATH=tests ../.venv/bin/mypy --strict --ignore-missing-imports pushlearn tests ../examples/python ../build_backend)
# The wheel (README.md, "One wheel"): built from the binaries above and the
# extension just installed (cargo builds nothing again), repaired into a
# manylinux wheel with libode inside, installed into a fresh virtual
# environment without Rust or the checkout, and run there.
scripts/wheel.sh --check
PUSHLEARN_REQUIRE_SIM=1 PUSHLEARN_SIM_BIN="$PWD/target/release/pushlearn-sim" PUSHLEARN_BIN="$PWD/target/release/pushlearn" \
  .venv/bin/python -m pytest -q python/tests
