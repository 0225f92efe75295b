#!/usr/bin/env bash
# v2.4's robustness at 1296 px on 12 new fingers (docs/training.md, "v2.4's robustness at
# 1296 px on 12 new fingers"): render the set (resumable; ~50 min on 2 cores), then one
# robustness bench of the shipped model on its 120 non-reference frames (~15 min), then the
# reading; then the same for H18-ab's A (its blur σ 12 row). Run from the repository root.
set -euo pipefail
C=.venv/bin/contactcal
T=data/rob_hr12
[[ -f $T/index.csv ]] || $C synth --workers 2 --quiet --fingers 12 --pressures 0:20:2 \
  --size 1296x972 --spp 8 --seed 41000 --hard-fraction 0.5 --out $T
[[ -f out/rob_hr12/results.json ]] || $C bench --data $T --model models/contact_unet.onnx \
  --robustness --robustness-frames 120 --repeats 1 --timing-frames 1 --out out/rob_hr12
.venv/bin/python docs/scripts/rob_hr12_report.py out/rob_hr12/results.json
# H18-ab's pointer on the same frames (docs/training.md, "Added at 16:00 UTC"): A, trained on
# 400-px renders only (docs/scripts/h18_ab.sh), scored by the same bench; read its blur σ 12 row.
[[ -f out/rob_hr12_A/results.json ]] || $C bench --data $T --model runs/h18ab_A/export.onnx \
  --robustness --robustness-frames 120 --repeats 1 --timing-frames 1 --out out/rob_hr12_A
.venv/bin/python docs/scripts/rob_hr12_report.py out/rob_hr12_A/results.json
