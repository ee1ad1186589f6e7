#!/usr/bin/env bash
# Installs what pushlearn needs on a Debian machine that has only the Rust
# toolchain, and nothing that is already there. Safe to run any number of times.
#
#   scripts/ensure-deps.sh            system packages for building and running
#   scripts/ensure-deps.sh --test     also what the test suite needs (Python protobuf,
#                                     Debian's chromium for the viewer's browser test)
set -euo pipefail

want_test=0
for arg in "$@"; do
  case "$arg" in
    --test) want_test=1 ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    *) echo "ensure-deps: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

missing=()
command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
if ! pkg-config --atleast-version=0.16 ode 2>/dev/null; then missing+=(libode-dev); fi
# bindgen loads libclang at build time.
if ! ls /usr/lib/llvm-*/lib/libclang.so* /usr/lib/x86_64-linux-gnu/libclang*.so* >/dev/null 2>&1; then
  missing+=(libclang-dev)
fi
command -v cc >/dev/null 2>&1 || missing+=(gcc)

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

if [ "$(pkg-config --variable=precision ode)" != "dDOUBLE" ]; then
  echo "ensure-deps: libode is not the double-precision build (pkg-config says '$(pkg-config --variable=precision ode)'); pushlearn needs Debian's libode-dev" >&2
  exit 1
fi

if [ "$want_test" = 1 ]; then
  if ! python3 -c 'import google.protobuf' >/dev/null 2>&1; then
    echo "ensure-deps: installing the Python 'protobuf' package for the Python package (python/)"
    python3 -m pip install --quiet 'protobuf>=4.21'
  fi
fi
