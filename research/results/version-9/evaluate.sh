#!/usr/bin/env bash
# The scores of research/results/version-9 (README.md): version 8 (V8, the baseline) and the candidate V9 (packed
# folders; version 8's three files are in git before version 9 replaced them, e.g. `git show
# 5702e44:python/frenbrdf/models/pretrained/model.pt`), on the 40 held-out tables of folds-v8 (4,000 random valid
# bins, draw 0, encoder and `latent`: the rule's reading) and the 19 measurements (encoder, `latent`, `full`: training data of V9); then
# the 40 tables through issue 47's six patterns at 300, 1,500 and 4,000 samples, encoder (and `latent` at 1,500).
# Two processes, one thread each (the patterns in two halves).
#
# LABELS names the two in the reports (default "v8 v9"; version 10 reads version 9 and its candidate as "v9 v10").
#
#   [LABELS="v9 v10"] bash research/results/version-9/evaluate.sh V8 V9 DATA OUT   (DATA: the 197 tables, local/fv8/data)
set -euo pipefail
V8=${1:?V8 packed folder}; V9=${2:?V9 packed folder}; DATA=${3:?DATA folder}; OUT=${4:?OUT folder}
HERE=$(dirname "$0")
COMPARE="python $HERE/../../studies/compare_models.py --models $V8 $V9 --labels ${LABELS:-v8 v9} --resolution 128"
FOLDS="python $HERE/../../studies/measured_folds/folds.py"
HELD_OUT=(--held-out "$HERE/../folds-v8/config-v8.json" "$DATA")
mkdir -p "$OUT"
OMP_NUM_THREADS=1 $COMPARE "${HELD_OUT[@]}" --budgets none latent --samples 4000 \
    --out "$OUT/tables" > "$OUT/tables.log" 2>&1 &
OMP_NUM_THREADS=1 $COMPARE --measurements ../shared/data/rgl-measured/*.bsdf --budgets none latent full \
    --samples 4000 --group $($FOLDS groups) \
    comparison-four=acrylic_felt_green_rgb,paper_white_rgb,vch_golden_yellow_rgb,cg_sunflower_rgb \
    --out "$OUT/measured" > "$OUT/measured.log" 2>&1 &
wait
for half in "merl-bins uniform in-plane" "gonioreflectometer image-based specular"; do
    OMP_NUM_THREADS=1 $COMPARE "${HELD_OUT[@]}" --budgets none latent --patterns $half \
        --samples 300 1500 4000 --refine-counts 1500 \
        --out "$OUT/patterns-${half%% *}" > "$OUT/patterns-${half%% *}.log" 2>&1 &
done
wait
