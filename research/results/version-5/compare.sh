#!/usr/bin/env bash
# Candidates for version 5 against version 4 (research/results/version-5): the same 42 held-out test materials of
# version 4's split (no candidate trained on them) and the real measurements none of them trained on (their split
# trained on the fits of 13 of the 19), through the six device patterns at 1,500 samples, encoder only
# (OUT/patterns), and from 4,000 random bins with the encoder, `latent` and `full` (OUT/refined). Two processes.
# Version 4 is a packed folder (python/frenbrdf/models/pretrained as shipped before), RUN the version-5 training
# work folder of release/train_shipped_model.py (its run/split.json and data/).
#
#   bash research/results/version-5/compare.sh RUN OUT LABEL=MODEL ...
set -euo pipefail
RUN=${1:?training work folder}; OUT=${2:?OUT folder}; shift 2
models=(); labels=()
for pair in "$@"; do labels+=("${pair%%=*}"); models+=("${pair#*=}"); done
tables=$(python research/studies/split_names.py tables "$RUN")
trained_on=$(python research/studies/split_names.py trained-on "$RUN" "${labels[@]}")
COMPARE=(python research/studies/compare_models.py --models "${models[@]}" --labels "${labels[@]}" --tables $tables
         --measurements ../shared/data/rgl-measured/*.bsdf --trained-on $trained_on --resolution 128)
mkdir -p "$OUT"
OMP_NUM_THREADS=1 "${COMPARE[@]}" --patterns merl-bins uniform in-plane gonioreflectometer image-based specular \
    --samples 1500 --budgets none --out "$OUT/patterns" > "$OUT/patterns.log" 2>&1 &
OMP_NUM_THREADS=1 "${COMPARE[@]}" --samples 4000 --budgets none latent full --out "$OUT/refined" > "$OUT/refined.log" 2>&1 &
wait
