#!/usr/bin/env bash
# The test suite, exactly what CI runs (README, "The two commands"):
# the Rust workspace's tests, then the Python package's (a fresh venv,
# `pip install crates/py`, pytest against the `nlvid` binary the first
# step built). Exit status non-zero if either failed; both always run.
#
#   scripts/test.sh                 # everything
#   NLVID_SKIP_PYTHON=1 scripts/test.sh   # the Rust tests only (no network)
set -uo pipefail
cd "$(dirname "$0")/.."
rc=0
cargo test --workspace || rc=$?
if [ -z "${NLVID_SKIP_PYTHON:-}" ]; then
    NLVID_BIN="${CARGO_TARGET_DIR:-target}/debug/nlvid" bash scripts/test-python.sh || rc=$?
fi
exit $rc
