#!/usr/bin/env bash
# H18-ab (docs/training.md, "H18-ab"): an exploratory, paired A/B of the blur share on the 400-px
# training sets only (v3_train, v3_onset), judged on a held-out 400-px set rendered for it. Not a
# ship candidate: the recipe's 1296-px sets are not on this machine. A is H17's command with
# fewer sets and epochs; B is A with --blur-p 0.6 (~18 % of frames beyond the suite's blur σ 12,
# against ~9 %). Same seed, split and initialisation. Run from the repository root; each step is
# skipped when its output exists (a killed training resumes from last.pt).
set -euo pipefail
C=.venv/bin/contactcal
T=data/h18ab_test
[[ -f $T/index.csv ]] || $C synth --workers 2 --quiet --fingers 12 --pressures 0:20:2 \
  --size 400x300 --spp 16 --seed 21000 --hard-fraction 0.5 --out $T
train() {  # NAME BLUR_P: train (resumable), export with the minimum area tuned on its validation
  local r=runs/h18ab_$1 resume=()
  [[ -f $r.commit ]] || { mkdir -p runs; git rev-parse HEAD > $r.commit; }
  [[ -f $r/last.pt ]] && resume=(--resume)
  [[ -f $r/val_bins.csv ]] || $C train --data data/v3_train data/v3_onset --out $r \
    --epochs 16 --input-size 192 --levels 4 --reference-dropout 0.3 --ridge-channel 288 \
    --contact-gain 0.3 1.5 --ridge-blur --blur-sigma 0.1 1.8 --blur-kernel 0 --blur-p "$2" \
    --threads 1 --norm-floor 1 --seed 1 --quiet "${resume[@]}"
  [[ -f $r/export.onnx ]] || $C export $r --out $r/export.onnx --tune-min-area
}
train A 0.3 & a=$!; train B 0.6 & b=$!; wait $a; wait $b  # each failure stops the script
mkdir -p out; p=()
for m in A B; do  # the same frames for both: the suite's draw depends on the set and the count
  [[ -f out/h18ab_rob_$m/results.json ]] || $C bench --data $T --model runs/h18ab_$m/export.onnx \
    --robustness --robustness-frames 120 --repeats 1 --timing-frames 1 \
    --out out/h18ab_rob_$m & p+=($!)
done
for q in "${p[@]}"; do wait "$q"; done
