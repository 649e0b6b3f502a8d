#!/usr/bin/env bash
# The attention-pooling study's scores (README.md): every model on version 4's 42 held-out test tables (RUN: a
# training work folder with run/split.json and data/, as release/train_shipped_model.py writes) and the real
# measurements none of them trained on, encoder only, through the six patterns at 1,500 samples (OUT/patterns) and
# from 4,000 random bins (OUT/random; with LATENT=1 `latent` too). With FAMILIES set, the same on that folder's tables
# instead. Two processes.
#
#   bash research/results/attention-pooling/compare.sh RUN OUT LABEL=MODEL ...        (the baseline first)
#   FAMILIES=local/att/families LATENT=1 bash research/results/attention-pooling/compare.sh RUN OUT LABEL=MODEL ...
set -euo pipefail
RUN=${1:?training work folder}; OUT=${2:?OUT folder}; shift 2
models=(); labels=()
for pair in "$@"; do labels+=("${pair%%=*}"); models+=("${pair#*=}"); done
if [[ -n ${FAMILIES:-} ]]; then
    scored=(--tables "$FAMILIES"/*.binary)
else
    tables=$(python research/studies/split_names.py tables "$RUN")
    trained_on=$(python research/studies/split_names.py trained-on "$RUN" "${labels[@]}")
    scored=(--tables $tables --measurements ../shared/data/rgl-measured/*.bsdf --trained-on $trained_on)
fi
COMPARE=(python research/studies/compare_models.py --models "${models[@]}" --labels "${labels[@]}" "${scored[@]}"
         --resolution 128)
mkdir -p "$OUT"
OMP_NUM_THREADS=1 "${COMPARE[@]}" --patterns merl-bins uniform in-plane gonioreflectometer image-based specular \
    --samples 1500 --budgets none --out "$OUT/patterns" > "$OUT/patterns.log" 2>&1 &
patterns=$!
OMP_NUM_THREADS=1 "${COMPARE[@]}" --samples 4000 --budgets none ${LATENT:+latent} --out "$OUT/random" > "$OUT/random.log" 2>&1 &
random=$!
wait "$patterns" || { echo "the patterns' comparison failed: $OUT/patterns.log" >&2; exit 1; }
wait "$random" || { echo "the random bins' comparison failed: $OUT/random.log" >&2; exit 1; }
