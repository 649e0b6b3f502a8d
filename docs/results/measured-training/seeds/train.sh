#!/usr/bin/env bash
# Seeds 1 and 3 of the control and of fold 1, from scratch, two runs at a time (one thread each).
# Data folders: local/v2/data (version 2's tables, benches/pretrained.sh) and local/folds/fold1 (the same plus
# acrylic_felt_green_rgb.bsdf and vch_golden_yellow_rgb.bsdf).
set -u
run() {  # name seed folder
  OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 frenbrdf train --data "$3" --seed "$2" --device cpu --quiet --json \
    --config docs/results/measured-training/config-scratch.json --out "local/folds/seed$2-$1" > "local/folds/seed$2-$1.log" 2>&1
}
for seed in 1 3; do
  run control "$seed" local/v2/data &
  run fold1 "$seed" local/folds/fold1 &
  wait
done
