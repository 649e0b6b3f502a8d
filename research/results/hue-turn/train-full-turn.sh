#!/usr/bin/env bash
# The hue_turn 1.0 runs (README.md beside this file): seeds 0 and 1 at once on the 2-core CPU, one thread
# each (the second 3 minutes later: reading ~170 tables peaks at ~13 GB), then seed 3 on both threads.
set -u
run() {
  frenbrdf train --data local/v2/data --config research/results/hue-turn/config-full-turn.json --seed $1 --device cpu \
    --quiet --json --out local/hue-turn/full-s$1 > local/hue-turn/full-s$1.log 2>&1
}
OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 run 0 &
sleep 180
OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 run 1 &
wait
OMP_NUM_THREADS=2 MKL_NUM_THREADS=2 run 3
