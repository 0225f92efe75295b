#!/usr/bin/env bash
# H15 (docs/training.md, "H15"): the recipe's chain (docs/scripts/chain.sh) with seed 0 and its
# validation sets data/val_v6*; outputs runs/h15, data/val_v6*, out/h15_*.
exec bash "$(dirname "$0")/chain.sh" h15 0 val_v6
