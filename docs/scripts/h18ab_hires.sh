#!/usr/bin/env bash
# H18-ab's follow-up (docs/training.md, "H18-ab"): A and B, trained on 400-px renders only, on a
# small held-out set rendered at 1296×972 as the recipe's validation sets are (4 fingers, half
# hard, 8 spp), to tell a world effect from a recipe effect in blur σ 12. Resumable; run after
# docs/scripts/h18_ab.sh.
set -euo pipefail
C=.venv/bin/contactcal
T=data/h18ab_test_hr
[[ -f $T/index.csv ]] || $C synth --workers 2 --quiet --fingers 4 --pressures 0:20:2 \
  --size 1296x972 --spp 8 --seed 21100 --hard-fraction 0.5 --out $T
p=()
for m in A B; do
  [[ -f out/h18ab_hr_$m/results.json ]] || $C bench --data $T --model runs/h18ab_$m/export.onnx \
    --robustness --robustness-frames 40 --repeats 1 --timing-frames 1 --out out/h18ab_hr_$m & p+=($!)
done
for q in "${p[@]}"; do wait "$q"; done
# Report only: the shipped v2.4 (trained on 1296-px sets too) on both H18-ab sets, the same frames.
[[ -f out/h18ab_rob_v24/results.json ]] || $C bench --data data/h18ab_test \
  --model models/contact_unet.onnx --robustness --robustness-frames 120 --repeats 1 \
  --timing-frames 1 --out out/h18ab_rob_v24 & a=$!
[[ -f out/h18ab_hr_v24/results.json ]] || $C bench --data $T --model models/contact_unet.onnx \
  --robustness --robustness-frames 40 --repeats 1 --timing-frames 1 --out out/h18ab_hr_v24 & b=$!
wait $a; wait $b
