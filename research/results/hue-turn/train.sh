#!/usr/bin/env bash
# The hue-turn study's runs (README.md beside this file): seeds 0 and 1 at once on the 2-core CPU, one
# thread each, on version 2's tables (local/v2/data, release/train_shipped_model.sh). Reading ~170 tables peaks at
# ~13 GB, so the second run starts 3 minutes after the first.
set -u
for seed in 0 1; do
  OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 frenbrdf train --data local/v2/data --config research/results/hue-turn/config.json \
    --seed $seed --device cpu --quiet --json --out local/hue-turn/s$seed > local/hue-turn/s$seed.log 2>&1 &
  [ $seed = 0 ] && sleep 180
done
wait
