#!/usr/bin/env bash
# The latent-steps study's scores (README.md): the shipped model's `latent` at 200 and 600 steps, on FAMILIES (the
# judging set) and on version 4's 42 test tables and the real measurements the model did not train on (RUN: a
# training work folder with run/split.json and data/, as release/train_shipped_model.py writes), from 4,000 random
# bins (OUT/*-random) and through the five device patterns at 1,500 (OUT/*-devices). One process at a time.
#
#   bash research/results/latent-steps/run.sh RUN FAMILIES OUT
set -euo pipefail
RUN=${1:?training work folder}; FAMILIES=${2:?families folder}; OUT=${3:?OUT folder}
tables=$(python research/studies/split_names.py tables "$RUN")
trained_on=$(python research/studies/split_names.py trained-on "$RUN" v7)
compare() {  # NAME, then the materials and what reads them
    local name=$1; shift
    OMP_NUM_THREADS=1 python research/studies/compare_models.py --models pretrained --labels v7 --resolution 128 \
        --budgets latent latent@latent_steps=600 --out "$OUT/$name" "$@" > "$OUT/$name.log" 2>&1 ||
        { echo "$name failed: $OUT/$name.log" >&2; exit 1; }
}
devices=(--patterns uniform in-plane gonioreflectometer image-based specular --samples 1500)
mkdir -p "$OUT"
compare families-random --tables "$FAMILIES"/*.binary --samples 4000
compare families-devices --tables "$FAMILIES"/*.binary "${devices[@]}"
python research/results/latent-steps/decide.py "$OUT" > "$OUT/decision.txt"
compare tables-random --tables $tables --measurements ../shared/data/rgl-measured/*.bsdf --trained-on $trained_on \
    --samples 4000
compare tables-devices --tables $tables --measurements ../shared/data/rgl-measured/*.bsdf --trained-on $trained_on \
    "${devices[@]}"
