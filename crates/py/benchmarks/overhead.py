"""Binding overhead: N calls through Python (nlvid.MetaModel.predict,
nlvid.fit_hertz) against the same N library calls in a Rust loop in the
same compiled module (nlvid._nlvid._bench_*). Prints per-call times and the
overhead; exits 1 when an overhead exceeds --limit (default 5 %).

    python crates/py/benchmarks/overhead.py [-n 1000] [--repeat 5]

Each figure is the best of --repeat runs (least disturbed by other load).
"""

import argparse
import csv
import math
import sys
import time
from pathlib import Path

import numpy as np

import nlvid
from nlvid import _nlvid

ROOT = Path(__file__).resolve().parents[3]


def best(f, repeat):
    return min(f() for _ in range(repeat))


def python_loop(call, n):
    def run():
        t0 = time.perf_counter()
        for _ in range(n):
            call()
        return time.perf_counter() - t0
    return run


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("-n", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--limit", type=float, default=0.05)
    ap.add_argument("--only", help="run one case on one side and time nothing (for "
                    "valgrind --tool=callgrind: instructions of N calls minus those of 0)")
    ap.add_argument("--side", choices=["python", "rust"], default="python")
    a = ap.parse_args()
    meta = ROOT / "examples/demo/metamodel"
    model = nlvid.MetaModel.load(meta / "model.json")
    with open(ROOT / "examples/demo/ground_truth.csv") as f:
        row = next(csv.DictReader(f))
    x = np.array([float(row[c]) for c in ["G0_Pa", "g1", "g2", "tau1_s", "tau2_s"]])
    # A Hertz curve (eq. 1.1) with a little deterministic "noise".
    s = np.linspace(4e-6, 1e-6, 2000)
    F = 1e-11 + 4.0 / 3.0 * 2e3 / 0.75 * math.sqrt(5e-6) * np.clip(3e-6 - s, 0, None) ** 1.5
    F = F + 1e-12 * np.sin(np.arange(len(s)))
    cases = [
        ("predict", lambda: model.predict(x),
         lambda: _nlvid._bench_predict(model, x, a.n)),
        ("predict+mse", lambda: model.predict(x, mse=True),
         lambda: _nlvid._bench_predict(model, x, a.n, mse=True)),
        ("fit_hertz", lambda: nlvid.fit_hertz(s, F, "5 um"),
         lambda: _nlvid._bench_fit_hertz(s, F, "5 um", a.n)),
    ]
    if a.only:
        name, py_call, rust_loop = next(c for c in cases if c[0] == a.only)
        if a.side == "python":
            for _ in range(a.n):
                py_call()
        else:
            rust_loop()
        return 0
    failed = False
    print(f"{a.n} calls, best of {a.repeat}")
    print(f"{'call':12s} {'python us/call':>15s} {'rust us/call':>13s} {'overhead':>9s}")
    for name, py_call, rust_loop in cases:
        py_call()  # warm up
        tp = best(python_loop(py_call, a.n), a.repeat)
        tr = best(rust_loop, a.repeat)
        over = tp / tr - 1
        failed |= over > a.limit
        print(f"{name:12s} {tp / a.n * 1e6:15.2f} {tr / a.n * 1e6:13.2f} {over * 100:8.2f}%")
    if failed:
        print(f"overhead above {a.limit * 100:.0f} %", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
