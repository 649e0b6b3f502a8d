#!/usr/bin/env bash
# The trainings of research/results/real-in-data (README.md): for each fold of measured_folds/folds.json, version
# 8's recipe (folds-v8/config-v8.json) on DATA (version 4's tables less the fits of the 19 measurements) plus the
# .bsdf measurements of the two other folds plus the procedural families of FAMILIES, seed 0, the three folds at
# once on one thread each.
#
#   bash research/results/real-in-data/train.sh DATA FAMILIES WORK [MEASURED]
set -euo pipefail
DATA=${1:?DATA folder}; FAMILIES=${2:?FAMILIES bank folder}; WORK=${3:?WORK folder}
MEASURED=${4:-../shared/data/rgl-measured}
HERE=$(dirname "$0")
CONFIG=$HERE/../folds-v8/config-v8.json
for fold in 0 1 2; do
    folder="$WORK/data-f$fold"
    mkdir -p "$folder"
    for path in "$DATA"/* "$FAMILIES"/*.binary; do ln -sfn "$(realpath "$path")" "$folder/"; done
    for name in $(python "$HERE/../../studies/measured_folds/folds.py" others "$fold"); do
        ln -sfn "$(realpath "$MEASURED/$name.bsdf")" "$folder/"
    done
done
for fold in 0 1 2; do echo "$fold"; done | OMP_NUM_THREADS=1 xargs -P 3 -L 1 bash -c \
    'frenbrdf train --data "$1/data-f$2" --config "$0" --seed 0 --out "$1/mf-f$2-s0" --quiet > "$1/mf-f$2-s0.log" 2>&1' \
    "$CONFIG" "$WORK"
