#!/usr/bin/env bash
# The third candidate's test set (research/results/version-5): the 45 procedural families (FAMILIES: `frenbrdf synth
# FAMILIES --n 45 --seed 0 --mix families`), which no model here trained on, through the six patterns at 1,500
# samples, encoder only (OUT/patterns), and from 4,000 random bins, encoder and `latent` (OUT/refined). Two processes.
#
#   bash research/results/version-5/compare_families.sh FAMILIES OUT LABEL=MODEL ...
set -euo pipefail
FAMILIES=${1:?FAMILIES folder}; OUT=${2:?OUT folder}; shift 2
models=(); labels=()
for pair in "$@"; do labels+=("${pair%%=*}"); models+=("${pair#*=}"); done
COMPARE=(python research/studies/compare_models.py --models "${models[@]}" --labels "${labels[@]}"
         --tables "$FAMILIES"/*.binary --resolution 128)
mkdir -p "$OUT"
OMP_NUM_THREADS=1 "${COMPARE[@]}" --patterns merl-bins uniform in-plane gonioreflectometer image-based specular \
    --samples 1500 --budgets none --out "$OUT/patterns" > "$OUT/patterns.log" 2>&1 &
OMP_NUM_THREADS=1 "${COMPARE[@]}" --samples 4000 --budgets none latent --out "$OUT/refined" > "$OUT/refined.log" 2>&1 &
wait
