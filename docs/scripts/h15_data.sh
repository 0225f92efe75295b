#!/usr/bin/env bash
# The sets of H15's rule (docs/training.md, "H15"): H14's seven training sets (same commands,
# same seeds), the validation sets val_r3, v2_cal and val_depart, the procedural choosing pair
# 7800/7900. Run from the repository root; each `contactcal synth` resumes a folder it left
# unfinished, and a finished folder is skipped, so a killed run is simply started again.
set -euo pipefail
S=".venv/bin/contactcal synth --workers 2 --quiet"
P=".venv/bin/contactcal procedural"
synth() {  # OUT ARGS...: render unless OUT holds a finished set (its index.csv)
  local out=$1; shift
  [[ -f $out/index.csv ]] || $S "$@" --out "$out"
}
synth data/v3_train --fingers 40 --pressures 0:20:1 --size 400x300 --spp 16 --seed 11000 \
  --hard-fraction 0.5 --speck-fraction 0.3
synth data/v3_onset --fingers 16 --pressures 0:6:0.5 --size 400x300 --spp 16 --seed 12000 \
  --hard-fraction 0.5 --speck-fraction 0.3
synth data/v3_hires --fingers 8 --pressures 0:20:1 --size 1296x972 --spp 8 --seed 16000 \
  --hard-fraction 0.5 --speck-fraction 0.3
synth data/v3_hires2 --fingers 10 --pressures 0:20:1 --size 1296x972 --spp 8 --seed 16100 \
  --hard-fraction 0.5 --speck-fraction 0.3
synth data/v3_hires3 --fingers 20 --pressures 0:20:1 --size 1296x972 --spp 8 --seed 16200 \
  --hard-fraction 0.5 --speck-fraction 0.3
synth data/v4_depart_train --fingers 20 --pressures 0:20:1 --size 1296x972 --spp 8 \
  --seed 18700 --hard-fraction 0.5 --speck-fraction 0.3 --departure-fraction 0.5
synth data/v4_depart_train2 --fingers 20 --pressures 0:20:1 --size 1296x972 --spp 8 \
  --seed 18800 --hard-fraction 0.5 --speck-fraction 0.3 --departure-fraction 1
synth data/val_r3 --fingers 10 --pressures 0:8:0.5 --size 1296x972 --spp 8 --seed 18000 \
  --hard-fraction 0.5
synth data/v2_cal --fingers 20 --pressures 0:20:2 --size 400x300 --spp 16 --seed 14000 \
  --hard-fraction 0.5  # v2.4's interval and gate set (on this machine already; the chain's too)
synth data/val_depart --fingers 8 --pressures 0:20:2 --size 1296x972 --spp 8 --seed 19200 \
  --hard-fraction 0.5 --departure-fraction 1
for seed in 7800 7900; do
  [[ -f data/cc${seed}_hr/index.csv ]] || $P --fingers 12 --pressures 0:20:1 \
    --size 1296x972 --seed $seed --out data/cc${seed}_hr
done
