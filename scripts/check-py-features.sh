#!/usr/bin/env bash
# Lists the shared dependencies that `pip install crates/py` would compile
# with other features than `cargo test --workspace` does (each one is
# rebuilt, with every crate above it, after the test build: minutes in CI).
# Exit status 1 if any is listed besides the pyo3 crates, whose
# `extension-module` feature only the Python build turns on. The fix is a
# line in crates/py/Cargo.toml's feature-alignment block.
set -euo pipefail
cd "$(dirname "$0")/.."
list() { cargo tree --locked "$@" -f '{p} {f}' --prefix none | sed 's/ (\*)$//; s/ (proc-macro)$//; s| (/[^)]*)||' | sort -u; }
ws=$(list --workspace -e normal,build,dev)
py=$(list -p nlvid-py --features nlvid-py/extension-module -e normal,build)
python3 - "$ws" "$py" <<'PY'
import sys
def parse(text):
    out = {}
    for line in text.splitlines():
        parts = line.split()
        if len(parts) >= 2:
            out.setdefault(" ".join(parts[:2]), set()).add(parts[2] if len(parts) > 2 else "")
    return out
ws, py = parse(sys.argv[1]), parse(sys.argv[2])
inherent = ("nlvid-py ", "pyo3 ", "pyo3-build-config ", "pyo3-ffi ")
bad = [k for k in sorted(py) if k in ws and ws[k] != py[k] and not k.startswith(inherent)]
for k in bad:
    print(f"{k}: test build {sorted(ws[k])}, Python build {sorted(py[k])}")
print("features aligned" if not bad else f"{len(bad)} dependencies differ")
sys.exit(1 if bad else 0)
PY
