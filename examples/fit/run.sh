#!/bin/sh
# Worked example of `nlvid fit` (run from examples/fit; seconds in a debug
# build). NLVID=path/to/nlvid overrides the binary on PATH. The same steps
# run as a test: crates/cli/tests/it/fit.rs.
set -e
NLVID=${NLVID:-nlvid}
mkdir -p work
python3 make_data.py
"$NLVID" sample --domain domain.toml -n 200 --check 40 --seed 1 --out work/design
"$NLVID" build --design work/design/train.csv --model hertz-prony --points 100 \
    --domain domain.toml --store work/store --export work/export --quiet
"$NLVID" build --design work/design/check.csv --model hertz-prony --points 100 \
    --domain domain.toml --store work/store-check --export work/export-check --quiet
# The force of this (linear viscoelastic) model is exactly proportional to
# G0, and G0, tau1, tau2 are designed on log axes: krige F/G0 in ln G0, ln tau
# (docs/cli/fit.md, "Choosing the surrogate").
"$NLVID" surrogate fit --x work/export/X.csv --y work/export/Y.csv \
    --regression poly1 --correlation gauss \
    --proportional-to G0 --log-inputs G0,tau1,tau2 -o work/model.json
# The measured checking error (max eq. 4.4 RMSE) is what `nlvid fit` compares
# the surrogate and real-model misfits with; `surrogate check` saves it next
# to the model as work/model.check.json, where `nlvid fit` looks.
"$NLVID" surrogate check work/model.json \
    --x work/export-check/X.csv --y work/export-check/Y.csv
"$NLVID" fit study.toml cell1.csv --plot work/plots
