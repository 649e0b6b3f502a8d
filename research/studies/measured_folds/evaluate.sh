#!/usr/bin/env bash
# The real-measurements fold study's scores (research/results/measured-folds): the runs without measurements
# (BASE-s0, -s1, …: the sampling-patterns study's runs of the same config, and WORK/fits-s2), the fold runs of
# train.sh and train_families.sh, and version 4 read the 19 measurements from 4,000 random valid bins (draw 0)
# with the encoder, `latent` and `full`; a fold run is scored only on the measurements of its own fold (it trained on the others).
# Then the 39 held-out tables: encoder by every run, `latent` by the seed-0 runs and v4 (v4 not on the tables it
# trained on). Two processes.
#
#   bash research/studies/measured_folds/evaluate.sh BASE CONFIG DATA WORK OUT
#   (BASE e.g. local/v5/study/mixed-mean; CONFIG the runs' config, whose `holdout` names the tables in DATA)
set -euo pipefail
BASE=${1:?BASE runs prefix}; CONFIG=${2:?CONFIG json}; DATA=${3:?DATA folder}; WORK=${4:?WORK folder}
OUT=${5:?OUT folder}
HERE=$(dirname "$0")
COMPARE="python $HERE/../compare_models.py"
models=(); labels=(); trained_on=()
shopt -s nullglob
for run in "$BASE"-s[0-9] "$WORK"/fits-s[0-9]; do models+=("$run"); labels+=("fits/${run##*-}"); done
for fold in 0 1 2; do
    others=$(python "$HERE/folds.py" others "$fold")
    for arm in measured families; do for seed in 0 1 2 3 4 5; do  # the finished runs (a log's last line names its folder)
        grep -qs "run folder" "$WORK/$arm-f$fold-s$seed.log" || continue
        models+=("$WORK/$arm-f$fold-s$seed"); labels+=("$arm/f$fold-s$seed")
        for name in $others; do trained_on+=("$arm/f$fold-s$seed=$name"); done
    done; done
done
# Version 4, on what it did not train on (its split's train and validation materials: v4-trained-on.txt).
models+=(pretrained); labels+=(v4)
while read -r name; do [[ -n "$name" ]] && trained_on+=("v4=$name"); done < "$HERE/../sampling_patterns/v4-trained-on.txt"
groups=$(python "$HERE/folds.py" groups)
mkdir -p "$OUT"
OMP_NUM_THREADS=1 $COMPARE --models "${models[@]}" --labels "${labels[@]}" --trained-on "${trained_on[@]}" \
    --measurements ../shared/data/rgl-measured/*.bsdf --budgets none latent full --samples 4000 --resolution 128 \
    --group $groups comparison-four=acrylic_felt_green_rgb,paper_white_rgb,vch_golden_yellow_rgb,cg_sunflower_rgb \
    --out "$OUT/measured" > "$OUT/measured.log" 2>&1 &
# The tables: every run encoder only (the rules' figure), then `latent` by the seed-0 runs and version 4 (a second a
# material: the sampling-patterns study's economy).
first=(); first_labels=(); first_trained_on=()
for i in "${!labels[@]}"; do
    [[ "${labels[$i]}" == */s0 || "${labels[$i]}" == */f?-s0 || "${labels[$i]}" == v4 ]] || continue
    first+=("${models[$i]}"); first_labels+=("${labels[$i]}")
    for pair in "${trained_on[@]}"; do [[ "$pair" == "${labels[$i]}="* ]] && first_trained_on+=("$pair"); done
done
{
    OMP_NUM_THREADS=1 $COMPARE --models "${models[@]}" --labels "${labels[@]}" --trained-on "${trained_on[@]}" \
        --held-out "$CONFIG" "$DATA" --budgets none --samples 4000 --resolution 128 \
        --out "$OUT/tables" > "$OUT/tables.log" 2>&1
    OMP_NUM_THREADS=1 $COMPARE --models "${first[@]}" --labels "${first_labels[@]}" --trained-on "${first_trained_on[@]}" \
        --held-out "$CONFIG" "$DATA" --budgets latent --samples 4000 --resolution 128 \
        --out "$OUT/tables-latent" > "$OUT/tables-latent.log" 2>&1
} &
wait
