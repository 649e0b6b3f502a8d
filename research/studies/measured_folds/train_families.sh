#!/usr/bin/env bash
# The procedural-families arm of the fold study (research/results/measured-folds): the `measured` runs of
# train.sh again, each fold's data plus a bank of FAMILIES (`frenbrdf synth FAMILIES --n 45 --seed 0 --mix
# families`: thin-film iridescence, pearlescent pigments, glitter), seeds 0 and 1 (seed 2 cut for time before any
# run: research/results/measured-folds), two at a time on one thread each.
#
#   bash research/studies/measured_folds/train_families.sh CONFIG WORK FAMILIES
set -euo pipefail
CONFIG=${1:?CONFIG json}; WORK=${2:?WORK folder of train.sh}; FAMILIES=${3:?FAMILIES bank folder}
source "$(dirname "$0")/../../../release/link_inputs.sh"
for fold in 0 1 2; do
    folder="$WORK/data-f$fold-families"
    mkdir -p "$folder"
    link_into "$folder" "$WORK/data-f$fold"/* "$FAMILIES"/*.binary
done
for seed in 0 1; do for fold in 0 1 2; do echo "$fold $seed"; done; done | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c \
    'frenbrdf train --data "$1/data-f$2-families" --config "$0" --seed "$3" --out "$1/families-f$2-s$3" --quiet \
        > "$1/families-f$2-s$3.log" 2>&1' "$CONFIG" "$WORK"
