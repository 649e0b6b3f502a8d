#!/usr/bin/env bash
# Issue 47's table for research/results/real-in-data (README.md): each `mf` run reads the measurements of its own
# fold through random bins and the five device patterns at 1,500 samples (draw 0: folds-v8's patterns-v8 draws),
# with its encoder, `latent`, and `latent` with the coverage weights of `frenbrdf reconstruct` (K = 32). One thread.
#
#   bash research/results/real-in-data/evaluate_patterns.sh WORK OUT
set -euo pipefail
WORK=${1:?WORK folder}; OUT=${2:?OUT folder}
HERE=$(dirname "$0")
FOLDS="python $HERE/../../studies/measured_folds/folds.py"
models=(); labels=(); trained_on=()
for fold in 0 1 2; do
    models+=("$WORK/mf-f$fold-s0"); labels+=("mf/f$fold-s0")
    for name in $($FOLDS others "$fold"); do trained_on+=("mf/f$fold-s0=$name"); done
done
mkdir -p "$OUT"
OMP_NUM_THREADS=1 python "$HERE/../../studies/compare_models.py" \
    --models "${models[@]}" --labels "${labels[@]}" --trained-on "${trained_on[@]}" \
    --measurements ../shared/data/rgl-measured/*.bsdf --samples 1500 \
    --patterns merl-bins uniform in-plane gonioreflectometer image-based specular \
    --budgets none latent latent@coverage_k=32 --resolution 128 --group $($FOLDS groups) \
    --out "$OUT/patterns-mf" > "$OUT/patterns-mf.log" 2>&1
