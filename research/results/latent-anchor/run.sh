#!/usr/bin/env bash
# The latent-anchor study's judging runs (README.md): `latent` as `frenbrdf reconstruct` reads a device (coverage
# weights, k 32) with and without the anchor (weight 0.03), through the five device patterns at 1,500 (draw 0):
#   OUT/measured: the 19 real measurements, by last stop's three fold candidates (PIPE/cand-s0 … s2, trained
#                 without any of the 19: folds-v8/pipeline);
#   OUT/families: 45 new procedural families (FAMILIES, seed 13), the shipped model.
# Two processes, one thread each.
#
#   bash research/results/latent-anchor/run.sh PIPE FAMILIES OUT
set -euo pipefail
PIPE=${1:?PIPE folder}; FAMILIES=${2:?families folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
COMPARE="python $HERE/../../studies/compare_models.py"
common=(--patterns uniform in-plane gonioreflectometer image-based specular --samples 1500 --resolution 128
        --budgets latent@coverage_k=32 latent@coverage_k=32,anchor=0.03)
mkdir -p "$OUT"
OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 $COMPARE --models "$PIPE"/cand-s{0,1,2} --labels pipe/s0 pipe/s1 pipe/s2 \
    --measurements ../shared/data/rgl-measured/*.bsdf "${common[@]}" \
    --group $(python "$HERE/../../studies/measured_folds/folds.py" groups) \
    --out "$OUT/measured" > "$OUT/measured.log" 2>&1 &
OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 $COMPARE --models pretrained --labels v8 --tables "$FAMILIES"/*.binary \
    "${common[@]}" --out "$OUT/families" > "$OUT/families.log" 2>&1 &
wait
python "$HERE/decide.py" "$OUT" > "$OUT/decision.txt"
