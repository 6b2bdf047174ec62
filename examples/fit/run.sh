#!/bin/sh
# Worked example of `nlvid fit` (run from examples/fit; seconds in a debug
# build). NLVID=path/to/nlvid overrides the binary on PATH. The same steps
# run as a test: crates/cli/tests/fit.rs.
set -e
NLVID=${NLVID:-nlvid}
mkdir -p work
python3 make_data.py
"$NLVID" sample --domain domain.toml -n 200 --check 40 --seed 1 --out work/design
"$NLVID" build --design work/design/train.csv --model hertz-prony --points 100 \
    --store work/store --export work/export --quiet
"$NLVID" build --design work/design/check.csv --model hertz-prony --points 100 \
    --store work/store-check --export work/export-check --quiet
"$NLVID" surrogate fit --x work/export/X.csv --y work/export/Y.csv \
    --regression poly1 --correlation gauss -o work/model.json
# The measured checking error (max eq. 4.4 RMSE) is what `nlvid fit` compares
# the surrogate and real-model misfits with: keep it next to the model.
"$NLVID" --json surrogate check work/model.json \
    --x work/export-check/X.csv --y work/export-check/Y.csv > work/model.check.json
"$NLVID" fit study.toml cell1.csv --plot work/plots
