#!/bin/sh
# Rebuilds everything in examples/demo from its two study files:
#   metamodel.toml  -> training/checking designs, forward-model runs,
#                      Kriging meta-model, its checking errors (metamodel/)
#   study.toml      -> (with metamodel.toml's [forward]) the cells' curves
#                      data/<group>/*.csv and ground_truth.csv
# Works for any forward model metamodel.toml names that `nlvid build` knows;
# the curve writer (`nlvid demo --write-data`, nlvid_forward::curves) runs
# the FE model for the cells.
# Deterministic: same study files -> same bytes (checked by
# `cargo test -p nlvid-report the_committed_demo`).
set -eu
cd "$(dirname "$0")"
NLVID=${NLVID:-"cargo run --release -q -p nlvid --"}
WORK=${WORK:-work}
rm -rf "$WORK"
mkdir -p metamodel

# 1. designs + forward-model runs (store, then export X/Y/meta.json)
$NLVID build metamodel.toml --store "$WORK/runs" --export "$WORK/export"
# 2. Kriging on the training runs (PCA of the force curves, one θ search)
$NLVID surrogate fit --x "$WORK/export/train/X.csv" --y "$WORK/export/train/Y.csv" \
    --regression poly1 --correlation gauss --pca 0.999999 --out metamodel/model.json
cp "$WORK/export/train/meta.json" metamodel/meta.json
# 3. checking errors (eq. 4.4) on the separate checking design
$NLVID --json surrogate check metamodel/model.json \
    --x "$WORK/export/check/X.csv" --y "$WORK/export/check/Y.csv" \
    --summary metamodel/check.json > /dev/null
# 4. the cells' curves and their ground truth
$NLVID demo --demo . --write-data
rm -rf "$WORK"
