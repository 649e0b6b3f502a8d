#!/usr/bin/env bash
# The trainings of research/results/real-in-data (README.md): for each fold of measured_folds/folds.json, version
# 8's recipe (folds-v8/config-v8.json) on DATA (version 4's tables less the fits of the 19 measurements) plus the
# .bsdf measurements of the two other folds plus the procedural banks of FAMILIES, as WORK/ARM-fF-sSEED (ARM default
# mf; research/results/diffractive names its arm mfd). One run per fold in FOLDS (default 0 1 2) and seed in SEEDS
# (default SEED, default 0), JOBS (default 3) at once on one thread each. CONFIG replaces version 8's recipe
# (research/results/latent-size), FRENBRDF the command that trains (research/results/fold-tie). RESUME=1 continues
# runs stopped midway from their last.pt.
#
#   [SEED=0 | SEEDS="0 1 2"] [FOLDS="0 1 2"] [ARM=mf] [CONFIG=FILE] [FRENBRDF=COMMAND] bash research/results/real-in-data/train.sh DATA FAMILIES WORK [MEASURED]
set -euo pipefail
DATA=${1:?DATA folder}; FAMILIES=${2:?FAMILIES bank folder}; WORK=${3:?WORK folder}
MEASURED=${4:-../shared/data/rgl-measured}
SEEDS=${SEEDS:-${SEED:-0}}; FOLDS=${FOLDS:-0 1 2}; ARM=${ARM:-mf}
HERE=$(dirname "$0")
source "$HERE/../../../release/link_inputs.sh"
CONFIG=${CONFIG:-$HERE/../folds-v8/config-v8.json}
export FRENBRDF=${FRENBRDF:-frenbrdf}
for fold in $FOLDS; do
    folder="$WORK/data-$ARM-f$fold"
    mkdir -p "$folder"
    link_into "$folder" "$DATA"/* "$FAMILIES"/*.binary
    for name in $(python "$HERE/../../studies/measured_folds/folds.py" others "$fold"); do
        link_into "$folder" "$MEASURED/$name.bsdf"
    done
done
for seed in $SEEDS; do for fold in $FOLDS; do echo "$fold $seed"; done; done | OMP_NUM_THREADS=1 xargs -P "${JOBS:-3}" -L 1 bash -c \
    '$FRENBRDF train --data "$1/data-$2-f$3" --config "$0" --seed "$4" --out "$1/$2-f$3-s$4" ${RESUME:+--resume} --quiet > "$1/$2-f$3-s$4.log" 2>&1' \
    "$CONFIG" "$WORK" "$ARM"
