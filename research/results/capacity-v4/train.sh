#!/usr/bin/env bash
# The capacity re-choice's two runs (README.md): version 4's recipe, as run on this CPU for version 5's control
# (BASE, e.g. local/v5/release/paper-s1: its config, data and 42 held-out tables), with the larger model of the
# capacity study; seeds 0 and 1, two at a time on one thread each.
#
#   bash research/results/capacity-v4/train.sh BASE DATA WORK
#   (DATA: version 4's tables, e.g. local/v5/release/work/data)
set -euo pipefail
BASE=${1:?}; DATA=${2:?}; WORK=${3:?}
mkdir -p "$WORK"
python research/results/capacity-v4/sized_config.py "$BASE/config.json" "$WORK/config.json"
for seed in 0 1; do echo "$seed"; done | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c \
    'frenbrdf train --data "$1" --config "$0/config.json" --seed "$2" --out "$0/big-s$2" --quiet \
        > "$0/big-s$2.log" 2>&1' "$WORK" "$DATA"
