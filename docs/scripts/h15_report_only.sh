#!/usr/bin/env bash
# H15's report-only sets (docs/training.md, "H15"): rendered after the rule, scored once after the
# decision, never used to choose. A fresh half-hard Mitsuba set at 1296×972 (seed 32000), two fresh
# procedural sets (32100, 32200) and the 400×300 set v2_check_31200; v2.4 and H15 in one run.
# Resumable like h15_data.sh (a finished folder, one with its index.csv, is skipped).
set -euo pipefail
C=.venv/bin/contactcal
# scored once, after the decision: the chain's verdict must exist
[[ -f out/h15_verdict.md ]] || { echo "h15_report_only: no out/h15_verdict.md yet" >&2; exit 2; }
[[ -f data/check_32000/index.csv ]] || $C synth --workers 2 --quiet --fingers 12 \
  --pressures 0:20:1 --size 1296x972 --spp 8 --seed 32000 --hard-fraction 0.5 \
  --out data/check_32000
for seed in 32100 32200; do
  [[ -f data/cc${seed}_hr/index.csv ]] || $C procedural --fingers 12 --pressures 0:20:1 \
    --size 1296x972 --seed $seed --out data/cc${seed}_hr
done
[[ -f data/v2_check_31200/index.csv ]] || $C synth --workers 2 --quiet --fingers 12 \
  --pressures 0:20:1 --size 400x300 --spp 16 --seed 31200 --hard-fraction 0.5 \
  --out data/v2_check_31200
# v2.4 from the history (models/ may hold H15 by then), checked by its sha256
[[ -f runs/v24.onnx ]] || git show 34c153a:models/contact_unet.onnx > runs/v24.onnx
sha256sum runs/v24.onnx | grep -q '^974304c41a3d4a96' || { echo "runs/v24.onnx: not v2.4" >&2; exit 2; }
[[ -f out/h15_report/results.json ]] || $C bench --data data/check_32000 --model runs/v24.onnx \
  --variant h15=runs/h15/v25.onnx --crosscheck data/cc32100_hr --crosscheck data/cc32200_hr \
  --crosscheck data/v2_check_31200 --repeats 1 --timing-frames 1 --out out/h15_report
