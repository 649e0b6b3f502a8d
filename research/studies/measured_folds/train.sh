#!/usr/bin/env bash
# The real-measurements fold study's trainings (research/results/measured-folds): for each of the three folds of
# folds.json and seeds 0, 1, 2, one run on DATA (the sampling-patterns study's folders: no measurement and no fit of
# one) plus the .bsdf measurements of the two other folds, with CONFIG (the sampling-patterns study's winner),
# two at a time on one thread each. The runs without measurements are that study's own runs of CONFIG (two
# seeds) and a third seed of them run here, WORK/fits-s2, so that both arms have three.
#
#   bash research/studies/measured_folds/train.sh DATA CONFIG WORK [MEASURED]
set -euo pipefail
DATA=${1:?DATA folder}; CONFIG=${2:?CONFIG json}; WORK=${3:?WORK folder}
MEASURED=${4:-../shared/data/rgl-measured}
HERE=$(dirname "$0")
source "$HERE/../../../release/link_inputs.sh"
for fold in 0 1 2; do
    folder="$WORK/data-f$fold"
    mkdir -p "$folder"
    link_into "$folder" "$DATA"/*
    python - "$HERE/folds.json" "$fold" <<'PY' | while read -r name; do link_into "$folder" "$MEASURED/$name.bsdf"; done
import json, sys
folds = json.load(open(sys.argv[1]))["folds"]
print("\n".join(name for k, fold in enumerate(folds) if k != int(sys.argv[2]) for name in fold))
PY
done
# One run per line: the data folder, the seed, the run's name.
{
    echo "$DATA 2 fits-s2"
    for seed in 0 1 2; do for fold in 0 1 2; do echo "$WORK/data-f$fold $seed measured-f$fold-s$seed"; done; done
} | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c \
    'frenbrdf train --data "$2" --config "$0" --seed "$3" --out "$1/$4" --quiet > "$1/$4.log" 2>&1' \
    "$CONFIG" "$WORK"
