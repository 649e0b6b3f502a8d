#!/usr/bin/env bash
# Six encoders for version 4's decoder (README.md beside this file): seeds 1-6, two chains at once on the
# 2-core CPU, one thread each, on version 4's tables (local/v4/work/data: version 2's, release/train_shipped_model.sh).
# Reading the tables peaks at ~13 GB, so the second chain starts 3 minutes after the first.
set -u
chain() {
  for seed in "$@"; do
    OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 frenbrdf train --data local/v4/work/data \
      --config research/results/encoder-mean-v4/config.json --seed $seed --device cpu --quiet --json \
      --out local/mean-v4/plain-s$seed > local/mean-v4/plain-s$seed.log 2>&1
  done
}
mkdir -p local/mean-v4
chain 1 2 3 &
sleep 180
chain 4 5 6 &
wait
