#!/usr/bin/env bash
# Seeds 1 and 3 of the control and of fold 1, from scratch, two runs at a time (one thread each).
# Data folders: local/v2/data (version 2's tables, release/train_shipped_model.sh) and local/folds/fold1 (the same plus
# acrylic_felt_green_rgb.bsdf and vch_golden_yellow_rgb.bsdf). Reading ~170 tables peaks at ~13 GB: two runs
# reading at once overflow 24 GB, so each run holds a lock for its first 3 minutes and waits for it to start.
set -u
run() {  # name seed folder
  (
    flock 9
    OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 frenbrdf train --data "$3" --seed "$2" --device cpu --quiet --json \
      --config research/results/measured-training/config-scratch.json --out "local/folds/seed$2-$1" \
      > "local/folds/seed$2-$1.log" 2>&1 9>&- &
    sleep 180
    flock -u 9
    wait
  ) 9> local/folds/.reading
}
lane() {  # name folder seeds...: one run after another, skipping those already trained
  local name=$1 folder=$2; shift 2
  for seed in "$@"; do
    [ -e "local/folds/seed$seed-$name/history.json" ] || run "$name" "$seed" "$folder"
  done
}
lane control local/v2/data 1 3 &
lane fold1 local/folds/fold1 1 3 &
wait
