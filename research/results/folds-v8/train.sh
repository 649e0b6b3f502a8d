#!/usr/bin/env bash
# The `v4` arm of research/results/folds-v8 (README.md): version 4's recipe on DATA (version 4's tables less the
# RGL fits of the 19 measurements), seeds 0, 1, 2, two at a time on one thread each. The `v8` arm runs on a lent
# GPU with research/studies/train-gpu.sh (README.md).
#
#   bash research/results/folds-v8/train.sh DATA WORK
set -euo pipefail
DATA=${1:?DATA folder}; WORK=${2:?WORK folder}
CONFIG=$(dirname "$0")/config-v4.json
mkdir -p "$WORK"
for seed in 0 1 2; do echo "$seed"; done | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c \
    'frenbrdf train --data "$1" --config "$0" --seed "$3" --out "$2/v4-s$3" --quiet > "$2/v4-s$3.log" 2>&1' \
    "$CONFIG" "$DATA" "$WORK"
