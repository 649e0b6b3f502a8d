#!/usr/bin/env bash
# decoder-finetune's reading through the devices (README.md; decides nothing): each fold's base run and its fitted
# copy, `latent` from 1,500 pairs of random bins and of the five device patterns, on the measurements the fold's run
# did not train on; one process a fold, two at a time.
#
#   bash research/results/decoder-finetune/devices.sh WORK FT OUT
set -euo pipefail
WORK=${1:?WORK folder of the base runs}; FT=${2:?folder of the fitted runs}; OUT=${3:?OUT folder}
STUDIES=$(dirname "$0")/../../studies
mkdir -p "$OUT"
for fold in 0 1 2; do echo "$fold"; done | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c '
    work=$1; ft=$2; out=$3; fold=$4; trained_on=()
    for m in $(python "$0/measured_folds/folds.py" others "$fold"); do trained_on+=("base/f$fold=$m" "ft/f$fold=$m"); done
    python "$0/compare_models.py" --models "$work/mfw512-f$fold-s0" "$ft/ft-f$fold" --labels "base/f$fold" "ft/f$fold" \
        --trained-on "${trained_on[@]}" --measurements ../shared/data/rgl-measured/*.bsdf --budgets latent \
        --patterns merl-bins uniform in-plane gonioreflectometer image-based specular --samples 1500 \
        --resolution 128 --out "$out/f$fold" > "$out/f$fold.log" 2>&1' "$STUDIES" "$WORK" "$FT" "$OUT"
