#!/usr/bin/env bash
# The scores of research/results/folds-v8 (README.md): the `v4` runs (the baseline, first), the `v8` runs and the
# shipped model (version 8, on the 6 measurements it did not train on) read the 19 measurements from 4,000 random
# valid bins (draw 0) with the encoder, `latent` and `full`; then the runs on the 40 held-out tables, encoder and
# `latent`. Two processes, one thread each.
#
#   bash research/results/folds-v8/evaluate.sh RUNS DATA OUT
#   (RUNS holds v4-s0 … v8-s2; DATA the tables the runs trained on, whose held-out ones are read)
set -euo pipefail
RUNS=${1:?RUNS folder}; DATA=${2:?DATA folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
COMPARE="python $HERE/../../studies/compare_models.py"
FOLDS="python $HERE/../../studies/measured_folds/folds.py"
models=(); labels=()
for arm in v4 v8; do for seed in 0 1 2; do models+=("$RUNS/$arm-s$seed"); labels+=("$arm/s$seed"); done; done
# The shipped model trained on the fits of 13 of the 19 (version 4's data and training split).
shipped_trained_on=()
while read -r name; do [[ -n "$name" ]] && shipped_trained_on+=("shipped=$name"); done \
    < "$HERE/../../studies/sampling_patterns/v4-trained-on.txt"
mkdir -p "$OUT"
OMP_NUM_THREADS=1 $COMPARE --models "${models[@]}" pretrained --labels "${labels[@]}" shipped \
    --trained-on "${shipped_trained_on[@]}" \
    --measurements ../shared/data/rgl-measured/*.bsdf --budgets none latent full --samples 4000 --resolution 128 \
    --group $($FOLDS groups) comparison-four=acrylic_felt_green_rgb,paper_white_rgb,vch_golden_yellow_rgb,cg_sunflower_rgb \
    --out "$OUT/measured" > "$OUT/measured.log" 2>&1 &
OMP_NUM_THREADS=1 $COMPARE --models "${models[@]}" --labels "${labels[@]}" \
    --held-out "$HERE/config-v8.json" "$DATA" --budgets none latent --samples 4000 --resolution 128 \
    --out "$OUT/tables" > "$OUT/tables.log" 2>&1 &
wait
