#!/bin/sh
# Worked example of `nlvid fit` (run from examples/fit; ~1 min in release).
set -e
mkdir -p work
python3 make_data.py
nlvid sample --domain domain.toml -n 200 --check 40 --seed 1 --out work/design
nlvid build --design work/design/train.csv --model hertz-prony --points 100 \
    --store work/store --export work/export --quiet
nlvid build --design work/design/check.csv --model hertz-prony --points 100 \
    --store work/store-check --export work/export-check --quiet
nlvid surrogate fit --x work/export/X.csv --y work/export/Y.csv \
    --regression poly1 --correlation gauss -o work/model.json
nlvid surrogate check work/model.json --x work/export-check/X.csv --y work/export-check/Y.csv
nlvid fit study.toml cell1.csv --plot work/plots
