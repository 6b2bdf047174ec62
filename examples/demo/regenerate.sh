#!/bin/sh
# Rebuilds everything in examples/demo from its two study files:
#   metamodel.toml  -> training/checking designs, forward-model runs,
#                      Kriging meta-model, its checking errors (metamodel/)
#   study.toml      -> (with metamodel.toml's [forward]) the cells' curves
#                      data/<group>/*.csv and ground_truth.csv
# The forward model is the FE cell model (afm-fe): N = 970 + 74 runs, about
# 8 min of CPU (0.43 s a run; both cores are used). The run store in $WORK
# is kept until the end, so an interrupted regenerate.sh resumes where it
# stopped when run again (a store of another study is refused).
# Deterministic: same study files -> same bytes (the data: checked by
# `cargo test -p nlvid-report the_committed_demo`). The committed
# metamodel/ and data/ were rebuilt by this script on session 23's FE
# solver (Newton tolerance 3e-5, docs/theory/fem.md "Session 23").
set -eu
cd "$(dirname "$0")"
NLVID=${NLVID:-"cargo run --release -q -p nlvid --"}
WORK=${WORK:-work}
mkdir -p metamodel

# 1. designs + forward-model runs (store, then export X/Y/meta.json)
$NLVID build metamodel.toml --store "$WORK/runs" --export "$WORK/export"
# 2. Kriging on the training runs (PCA of the force curves, one θ search);
#    the file holds what prediction needs (the MSE's Cholesky factor is
#    rebuilt from the sites and θ when loaded). One thread: the θ search's
#    parallel sums round differently from run to run on two threads (θ
#    then differs in the 4th digit); on one it is the same bytes.
RAYON_NUM_THREADS=1 $NLVID surrogate fit --x "$WORK/export/train/X.csv" --y "$WORK/export/train/Y.csv" \
    --regression poly1 --correlation gauss --pca 0.999999 --out metamodel/model.json
cp "$WORK/export/train/meta.json" metamodel/meta.json
# 3. checking errors (eq. 4.4) on the separate checking design
$NLVID --json surrogate check metamodel/model.json \
    --x "$WORK/export/check/X.csv" --y "$WORK/export/check/Y.csv" \
    --summary metamodel/check.json > /dev/null
# 4. the cells' curves and their ground truth (16 FE runs)
$NLVID demo --demo . --write-data
rm -rf "$WORK"
