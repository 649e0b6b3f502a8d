#!/usr/bin/env bash
# Issue 47's per-pattern figures on the 19 measurements under research/results/folds-v8's fold (README.md): ARM's
# three runs (v4 or v8) read each measurement through the six patterns at 1,500 samples (draw 0), encoder (each
# run's own, trained on random bins only), `latent`, and `latent` with the coverage weights that `frenbrdf
# reconstruct` gives a device's samples (K = 32). One thread.
#
#   bash research/results/folds-v8/evaluate_patterns.sh RUNS ARM OUT
set -euo pipefail
RUNS=${1:?RUNS folder}; ARM=${2:?v4 or v8}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
mkdir -p "$OUT"
OMP_NUM_THREADS=1 python "$HERE/../../studies/compare_models.py" \
    --models "$RUNS/$ARM-s0" "$RUNS/$ARM-s1" "$RUNS/$ARM-s2" --labels "$ARM/s0" "$ARM/s1" "$ARM/s2" \
    --measurements ../shared/data/rgl-measured/*.bsdf --samples 1500 \
    --patterns merl-bins uniform in-plane gonioreflectometer image-based specular \
    --budgets none latent latent@coverage_k=32 --resolution 128 \
    --group $(python "$HERE/../../studies/measured_folds/folds.py" groups) \
    --out "$OUT/patterns-$ARM" > "$OUT/patterns-$ARM.log" 2>&1
