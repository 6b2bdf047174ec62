#!/bin/sh
# Regenerates the synthetic capsule curves and figures in examples/capsule/data
# from known parameters with the `capsule-fe` forward model (thesis capsule,
# §4.3; default 0.3 mm force mesh; d = 1.5 mm; 1200 output times):
# Material Sets 1 and 2 of §4.4.2 under RH and RR, and §4.4.3's RH set with
# two sets of the same C1 + C2 but alpha = 0 and 0.5 under RH
# (crates/forward/examples/capsule_sets.rs). Deterministic: same code ->
# same bytes. Seven FE runs, about 1-2 CPU-min on an idle machine.
set -eu
cd "$(dirname "$0")/../.."
cargo run --release -q -p nlvid-forward --example capsule_sets -- examples/capsule/data
