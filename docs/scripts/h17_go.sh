#!/usr/bin/env bash
# H17 from wherever it stands (docs/training.md, "H17"): the renders of h15_data.sh in their own
# session at autogroup nice 19, the chain (chain.sh h17 1 val_v7 h17) as soon as the seven training
# sets are finished, and the chain again once every set is (its restatements and benches need the
# validation sets, which render beside the training). Every step resumes, so after a killed run
# (a session's end) this is simply started again. Run from the repository root:
#   setsid nohup bash docs/scripts/h17_go.sh >> logs/h17_go.log 2>&1 < /dev/null &
set -euo pipefail
mkdir -p logs
TRAINING=(v3_train v3_onset v3_hires v3_hires2 v3_hires3 v4_depart_train v4_depart_train2)
renders() { pgrep -f "bash docs/scripts/h15_data.sh" | head -1; }
if [[ -z $(renders) ]]; then
  setsid nohup bash docs/scripts/h15_data.sh >> logs/h15_data.log 2>&1 < /dev/null &
  sleep 2
fi
pid=$(renders)
[[ -n $pid ]] && echo 19 > "/proc/$pid/autogroup"  # the renders yield to the training
echo "$(date -u +%H:%M) renders: process ${pid:-none (finished)}"
for s in "${TRAINING[@]}"; do
  until [[ -f data/$s/index.csv ]]; do
    [[ -n $(renders) ]] || { echo "h17_go: the renders stopped before data/$s" >&2; exit 2; }
    sleep 60
  done
done
echo "$(date -u +%H:%M) training sets finished: the chain starts"
if ! bash docs/scripts/chain.sh h17 1 val_v7 h17; then
  echo "$(date -u +%H:%M) chain stopped (validation sets still rendering?): waiting for the renders"
  while [[ -n $(renders) ]]; do sleep 60; done
  bash docs/scripts/chain.sh h17 1 val_v7 h17
fi
echo "$(date -u +%H:%M) done: out/h17_verdict.md"
