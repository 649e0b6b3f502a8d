#!/usr/bin/env bash
# The trainings of research/results/real-in-data (README.md): for each fold of measured_folds/folds.json, version
# 8's recipe (folds-v8/config-v8.json) on DATA (version 4's tables less the fits of the 19 measurements) plus the
# .bsdf measurements of the two other folds plus the procedural banks of FAMILIES, seed SEED (default 0), the three
# folds at once on one thread each, as WORK/ARM-fF-sSEED (ARM default mf; research/results/diffractive names its
# arm mfd).
#
#   [SEED=0] [ARM=mf] bash research/results/real-in-data/train.sh DATA FAMILIES WORK [MEASURED]
set -euo pipefail
DATA=${1:?DATA folder}; FAMILIES=${2:?FAMILIES bank folder}; WORK=${3:?WORK folder}
MEASURED=${4:-../shared/data/rgl-measured}
SEED=${SEED:-0}; ARM=${ARM:-mf}
HERE=$(dirname "$0")
source "$HERE/../../../release/link_inputs.sh"
CONFIG=$HERE/../folds-v8/config-v8.json
for fold in 0 1 2; do
    folder="$WORK/data-$ARM-f$fold"
    mkdir -p "$folder"
    link_into "$folder" "$DATA"/* "$FAMILIES"/*.binary
    for name in $(python "$HERE/../../studies/measured_folds/folds.py" others "$fold"); do
        link_into "$folder" "$MEASURED/$name.bsdf"
    done
done
for fold in 0 1 2; do echo "$fold"; done | OMP_NUM_THREADS=1 xargs -P 3 -L 1 bash -c \
    'frenbrdf train --data "$1/data-$2-f$4" --config "$0" --seed "$3" --out "$1/$2-f$4-s$3" --quiet > "$1/$2-f$4-s$3.log" 2>&1' \
    "$CONFIG" "$WORK" "$ARM" "$SEED"
