#!/usr/bin/env bash
# The test suite, exactly what CI runs (README, "The two commands"):
# the Rust workspace's tests (unit, integration and doc tests; the examples
# and benches are not built here: `cargo clippy --all-targets` compiles
# them in CI), then the Python package's (a fresh venv, `pip install
# crates/py`, pytest against the `nlvid` binary the first step built).
# Exit status non-zero if either failed; all steps always run.
#
#   scripts/test.sh                 # everything
#   NLVID_SKIP_PYTHON=1 scripts/test.sh   # the Rust tests only (no network)
set -uo pipefail
cd "$(dirname "$0")/.."
rc=0
cargo test --workspace --lib --bins --tests || rc=$?
cargo test --workspace --doc || rc=$?
if [ -z "${NLVID_SKIP_PYTHON:-}" ]; then
    NLVID_BIN="${CARGO_TARGET_DIR:-target}/debug/nlvid" bash scripts/test-python.sh || rc=$?
fi
exit $rc
