#!/usr/bin/env bash
# The pipeline amendment's scores (../README.md): the three `pipe` candidates (PIPE/cand-s0 … s2) beside the three
# `v8` runs (RUNS/v8-s0 … s2) read the 19 measurements from 4,000 random valid bins (draw 0), encoder, `latent` and
# `full`; and the `pipe` candidates through the six patterns at 1,500 (draw 0, the same samples as the `v8` runs'
# patterns-v8 report, which summarise.py --arms v8 pipe pairs with them). Two processes, one thread each.
#
#   bash research/results/folds-v8/pipeline/evaluate.sh RUNS PIPE OUT
set -euo pipefail
RUNS=${1:?RUNS folder}; PIPE=${2:?PIPE folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
COMPARE="python $HERE/../../../studies/compare_models.py"
GROUPS_=$(python "$HERE/../../../studies/measured_folds/folds.py" groups)
mkdir -p "$OUT"
OMP_NUM_THREADS=1 $COMPARE --models "$RUNS"/v8-s{0,1,2} "$PIPE"/cand-s{0,1,2} \
    --labels v8/s0 v8/s1 v8/s2 pipe/s0 pipe/s1 pipe/s2 \
    --measurements ../shared/data/rgl-measured/*.bsdf --budgets none latent full --samples 4000 --resolution 128 \
    --group $GROUPS_ comparison-four=acrylic_felt_green_rgb,paper_white_rgb,vch_golden_yellow_rgb,cg_sunflower_rgb \
    --out "$OUT/measured" > "$OUT/measured.log" 2>&1 &
OMP_NUM_THREADS=1 $COMPARE --models "$PIPE"/cand-s{0,1,2} --labels pipe/s0 pipe/s1 pipe/s2 \
    --measurements ../shared/data/rgl-measured/*.bsdf --samples 1500 \
    --patterns merl-bins uniform in-plane gonioreflectometer image-based specular \
    --budgets none latent latent@coverage_k=32 --resolution 128 --group $GROUPS_ \
    --out "$OUT/patterns-pipe" > "$OUT/patterns-pipe.log" 2>&1 &
wait
