#!/usr/bin/env bash
# Python package test: a fresh virtual environment, `pip install crates/py`
# (pip fetches maturin from PyPI and builds the extension from the workspace
# crates), the `nlvid` binary the tests compare with, then pytest.
#
#   scripts/test-python.sh                          # dev profile (opt-level 1/2): quicker to build
#   NLVID_PY_PROFILE=release scripts/test-python.sh # the build users get from `pip install crates/py`
#   NLVID_BIN=target/debug/nlvid scripts/test-python.sh  # reuse a built CLI
#
# Needs: python3 (>= 3.9) with venv, cargo, network access to PyPI (numpy,
# pytest, maturin). Exit status: pytest's (0 = all passed).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_INCREMENTAL=0
export CI="${CI:-1}"
root=$PWD
venv="${NLVID_PY_VENV:-$root/target/py-venv}"
profile="${NLVID_PY_PROFILE:-dev}"
t0=$SECONDS

echo "== venv $venv"
python3 -m venv --clear "$venv"
"$venv/bin/python" -m pip install -q --disable-pip-version-check numpy pytest
# afmformats (optional for the package) lets test_afmformats.py compare its
# reading of the public JPK files with nlvid's; without it those tests are
# skipped with a message. Wheels only: a few seconds from PyPI.
"$venv/bin/python" -m pip install -q --disable-pip-version-check --only-binary=:all: afmformats \
    || echo "   afmformats not installable: its comparison tests will be skipped"

echo "== pip install crates/py (maturin, profile $profile)"
# --locked: the extension builds from the workspace's Cargo.lock, as CI does.
export MATURIN_PEP517_ARGS="--locked --profile $profile"
"$venv/bin/python" -m pip install -q --disable-pip-version-check "$root/crates/py"
echo "   built and installed in $((SECONDS - t0)) s"

# The tests compare every entry point with the `nlvid` binary. NLVID_BIN
# (e.g. target/debug/nlvid right after `cargo test --workspace`, which
# builds it) skips this build.
if [ -z "${NLVID_BIN:-}" ]; then
    echo "== nlvid binary for the comparisons"
    cargo build --locked -q -p nlvid
    export NLVID_BIN="${CARGO_TARGET_DIR:-$root/target}/debug/nlvid"
fi

# Absolute: pytest runs from crates/py/tests.
NLVID_BIN="$(cd "$(dirname "$NLVID_BIN")" && pwd)/$(basename "$NLVID_BIN")"
export NLVID_BIN

echo "== pytest"
cd "$root/crates/py/tests"   # not the source tree's python/ (the installed package is tested)
rc=0
"$venv/bin/python" -m pytest -q -p no:cacheprovider . || rc=$?
echo "python tests finished in $((SECONDS - t0)) s"
exit $rc
