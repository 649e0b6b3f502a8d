#!/usr/bin/env bash
# Issue 47's per-pattern table on the 19 real measurements (README.md): the fold study's runs and version 6, each
# scored only on the measurements outside its training, encoder at 300, 1,500 and 4,000 samples and `latent` at
# 1,500, through six patterns. Two processes.
#
#   bash research/results/patterns-measured/run.sh STUDY WORK OUT
#   (STUDY: the sampling-patterns study's runs, e.g. local/v5/study; WORK: the fold study's, e.g. local/v5/folds)
set -euo pipefail
STUDY=${1:?}; WORK=${2:?}; OUT=${3:?}
models=("$STUDY"/mixed-mean-s0 "$STUDY"/mixed-mean-s1 "$WORK"/fits-s2); labels=(fits/s0 fits/s1 fits/s2); trained_on=()
for fold in 0 1 2; do
    others=$(python research/studies/measured_folds/folds.py others "$fold")
    for seed in 0 1 2; do
        models+=("$WORK/measured-f$fold-s$seed"); labels+=("measured/f$fold-s$seed")
        for name in $others; do trained_on+=("measured/f$fold-s$seed=$name"); done
    done
done
models+=(pretrained); labels+=(v6)
while read -r name; do [[ -n "$name" ]] && trained_on+=("v6=$name"); done < research/studies/sampling_patterns/v4-trained-on.txt
groups=$(python research/studies/measured_folds/folds.py groups)
COMPARE=(python research/studies/compare_models.py --models "${models[@]}" --labels "${labels[@]}"
         --trained-on "${trained_on[@]}" --measurements ../shared/data/rgl-measured/*.bsdf --group $groups
         --patterns merl-bins uniform in-plane gonioreflectometer image-based specular --resolution 128)
mkdir -p "$OUT"
OMP_NUM_THREADS=1 "${COMPARE[@]}" --samples 300 1500 4000 --budgets none --out "$OUT/encoder" > "$OUT/encoder.log" 2>&1 &
encoder=$!
OMP_NUM_THREADS=1 "${COMPARE[@]}" --samples 1500 --budgets latent --out "$OUT/latent" > "$OUT/latent.log" 2>&1 &
latent=$!
wait "$encoder" || { echo "the encoder's comparison failed: $OUT/encoder.log" >&2; exit 1; }
wait "$latent" || { echo "the latent comparison failed: $OUT/latent.log" >&2; exit 1; }
