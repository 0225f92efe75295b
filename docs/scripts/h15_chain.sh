#!/usr/bin/env bash
# H15 (docs/training.md, "H15"): train, restate, score against v2.4 as the rule reads.
# Run from the repository root once the sets of the rule are rendered; outputs runs/h15, data/val_v6*,
# out/h15_*. Every step is skipped when its output exists, so a killed run is simply rerun.
set -euo pipefail
C=.venv/bin/contactcal
PY=.venv/bin/python
R=runs/h15
# the floored camera augmentation (658f4ff, amended rule) must be in the code that trains
git merge-base --is-ancestor 658f4ff HEAD || { echo "h15_chain: check out 658f4ff or later" >&2; exit 2; }
mkdir -p $R out
[[ -f $R/commit ]] || git rev-parse HEAD > $R/commit  # the code the run started with
if [[ ! -f $R/val_bins.csv ]]; then  # written last by a finished run
  RESUME=()
  [[ -f $R/last.pt ]] && RESUME=(--resume)
  $C train --data data/v3_train data/v3_onset data/v3_hires data/v3_hires2 data/v3_hires3 \
    data/v4_depart_train data/v4_depart_train2 --out $R --epochs 22 --input-size 192 --levels 4 \
    --reference-dropout 0.3 --ridge-channel 288 --contact-gain 0.3 1.5 --ridge-blur \
    --blur-kernel 5 --threads 2 --norm-floor 1 --quiet "${RESUME[@]}"
fi
[[ -f $R/export.onnx ]] || $C export $R --out $R/export.onnx --tune-min-area
[[ -f $R/convex.onnx ]] || $PY -m contactcal.train.interval $R/export.onnx --data data/v2_cal \
  --region convex --out $R/convex.onnx
[[ -f $R/gate.onnx ]] || $PY -m contactcal.train.change_gate $R/convex.onnx \
  --data data/val_r3 data/v2_cal --speck 0.1 0.2 0.4 --draws 3 --out $R/gate.onnx
[[ -f $R/v25.onnx ]] || $PY -m contactcal.train.interval $R/gate.onnx --data data/v2_cal \
  --out $R/v25.onnx
for pair in hires:val_v6 v4_depart:val_v6_depart v3_onset:val_v6_onset; do
  [[ -f data/${pair#*:}/index.csv ]] || \
    $PY docs/scripts/val_subset.py $R --match "${pair%%:*}" --out "data/${pair#*:}"
done
[[ -f out/h15_choose/results.json ]] || $C bench --data data/val_v6 --variant h15=$R/v25.onnx \
  --crosscheck data/val_v6_depart --crosscheck data/val_v6_onset --crosscheck data/val_depart \
  --crosscheck data/val_r3 --crosscheck data/v2_cal --crosscheck data/cc7800_hr \
  --crosscheck data/cc7900_hr --repeats 1 --timing-frames 1 --out out/h15_choose
for m in v24:models/contact_unet.onnx h15:$R/v25.onnx; do
  [[ -f out/h15_rob_${m%%:*}/results.json ]] || $C bench --data data/val_v6 --model "${m#*:}" \
    --robustness --robustness-frames 80 --repeats 1 --timing-frames 1 --out "out/h15_rob_${m%%:*}"
done
[[ -f out/h15_noref/results.json ]] || $C bench --data data/val_v6 --variant h15=$R/v25.onnx \
  --no-reference --repeats 1 --timing-frames 1 --out out/h15_noref  # reported, not in the rule
$PY docs/scripts/h15_rule.py out/h15_choose/results.json out/h15_rob_v24/results.json \
  out/h15_rob_h15/results.json > out/h15_verdict.md.tmp  # exit 2: no verdict, nothing kept
mv out/h15_verdict.md.tmp out/h15_verdict.md && cat out/h15_verdict.md
