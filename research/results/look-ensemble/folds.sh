#!/usr/bin/env bash
# look-ensemble's fold reading (README.md; reported only): for each of the shipped recipe's seed-0 fold runs
# (RUNS/mf-fF-s0, trained on RUNS/data-mf-fF, which holds no measurement of fold F) two more looks, seeds 2 and 3, as
# second-look's fold reading trained its seed-1 look (LOOKS/look-fF); then folds.py reads each fold's measurements
# through one look (seed 1) and the three averaged, both taken twice.
#
#   bash research/results/look-ensemble/folds.sh RUNS LOOKS OUT   (RUNS: local/rid, LOOKS: local/slf)
set -euo pipefail
RUNS=${1:?RUNS folder}; LOOKS=${2:?LOOKS folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
mkdir -p "$OUT"
# two at a time: a look's training holds about 7 GB
for seed in 2 3; do for fold in 0 1 2; do echo "$fold $seed"; done; done | xargs -P 2 -L 1 bash -c '
    [ -f "$2/look-f$3-s$4/done" ] && exit 0
    OMP_NUM_THREADS=1 python "$0/../../studies/second_look.py" train "$1/mf-f$3-s0/config.json" "$1/data-mf-f$3" \
        --base "$1/mf-f$3-s0" --out "$2/look-f$3-s$4" --epochs 300 --minutes 600 --seed "$4" --quiet \
        > "$2/look-f$3-s$4.log" 2>&1 && touch "$2/look-f$3-s$4/done"' "$HERE" "$RUNS" "$LOOKS"
OMP_NUM_THREADS=2 python "$HERE/folds.py" --runs "$RUNS" --looks "$LOOKS" --out "$OUT" > "$OUT/folds.log" 2>&1
