#!/usr/bin/env bash
# The latent-coverage study's scores (README.md): the shipped model's `latent` with and without coverage weights
# (coverage_k 32), on FAMILIES (the judging set) and on version 4's 42 test tables and the real measurements the
# model did not train on (RUN: a training work folder with run/split.json and data/, as
# release/train_shipped_model.py writes), from 4,000 random bins (OUT/*-random) and through the five device patterns
# at 1,500 (OUT/*-devices). Two processes at a time, one thread each.
#
#   bash research/results/latent-coverage/run.sh RUN FAMILIES OUT
set -euo pipefail
RUN=${1:?training work folder}; FAMILIES=${2:?families folder}; OUT=${3:?OUT folder}
tables=$(python research/studies/split_names.py tables "$RUN")
trained_on=$(python research/studies/split_names.py trained-on "$RUN" v8)
compare() {  # NAME, then the materials and what reads them
    local name=$1; shift
    OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 python research/studies/compare_models.py --models pretrained --labels v8 \
        --resolution 128 --budgets latent latent@coverage_k=32 --out "$OUT/$name" "$@" > "$OUT/$name.log" 2>&1 ||
        { echo "$name failed: $OUT/$name.log" >&2; exit 1; }
}
devices=(--patterns uniform in-plane gonioreflectometer image-based specular --samples 1500)
mkdir -p "$OUT"
compare families-random --tables "$FAMILIES"/*.binary --samples 4000 &
compare families-devices --tables "$FAMILIES"/*.binary "${devices[@]}"
wait
python research/results/latent-coverage/decide.py "$OUT" > "$OUT/decision.txt"
measured=(--measurements ../shared/data/rgl-measured/*.bsdf --trained-on $trained_on)
compare tables-random --tables $tables "${measured[@]}" --samples 4000 &
compare tables-devices --tables $tables "${measured[@]}" "${devices[@]}"
wait
