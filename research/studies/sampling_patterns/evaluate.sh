#!/usr/bin/env bash
# The sampling-patterns study's scores (research/results/sampling-patterns): every run of train.sh and the
# shipped version 4 read the 39 held-out tables and the 19 real measurements through six patterns at 300, 1,500
# and 4,000 samples (encoder only), and at 1,500 refined (`latent`). Version 4 is not scored on what it trained
# on (its split's train and validation materials, the fits of 13 of the measurements among them:
# v4-trained-on.txt). Two processes (the runs of one half each), then one summary over all rows.
#
#   bash research/studies/sampling_patterns/evaluate.sh DATA WORK OUT
set -euo pipefail
DATA=${1:?DATA folder}; WORK=${2:?WORK folder of train.sh}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
COMPARE="python $HERE/../compare_models.py"
COMMON=(--measurements ../shared/data/rgl-measured/*.bsdf --held-out "$HERE/paper-mean.json" "$DATA"
        --patterns merl-bins uniform in-plane gonioreflectometer image-based specular --samples 300 1500 4000
        --refine-counts 1500 --resolution 128)
labels() { for run in "$@"; do echo "${run%-s*}/${run##*-s}"; done; }
half() { local runs=("$@"); local models=(); for run in "${runs[@]}"; do models+=("$WORK/$run"); done
         echo "${models[@]}"; }
A=(paper-mean-s0 instruments-mean-s0 instruments-density-s0 paper-density-s0 paper-mean-s1 instruments-mean-s1)
B=(instruments-density-s1 paper-density-s1 paper-mean-s2 instruments-mean-s2 instruments-density-s2 paper-density-s2)
trained_on=(); while read -r name; do trained_on+=("v4=$name"); done < "$HERE/v4-trained-on.txt"
OMP_NUM_THREADS=1 $COMPARE --models $(half "${A[@]}") --labels $(labels "${A[@]}") "${COMMON[@]}" \
    --out "$OUT/a" > "$OUT/a.log" 2>&1 &
OMP_NUM_THREADS=1 $COMPARE --models pretrained $(half "${B[@]}") --labels v4 $(labels "${B[@]}") "${COMMON[@]}" \
    --trained-on "${trained_on[@]}" --out "$OUT/b" > "$OUT/b.log" 2>&1 &
wait
python "$HERE/merge.py" "$OUT/a/compare.json" "$OUT/b/compare.json" --out "$OUT"
