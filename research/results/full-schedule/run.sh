#!/usr/bin/env bash
# full-schedule's readings (README.md): `full` as shipped and the candidate schedule, on the 19 measurements (each by
# the shipped recipe's fold run that did not train on it, WORK/mf-fF-s0) and on the 40 held-out tables (the shipped
# model, which never trained on them), 4,000 random bins of draw 3, 128²; all of it once on one thread and once
# on two (OUT/t1, OUT/t2).
#
#   bash research/results/full-schedule/run.sh WORK DATA OUT     (WORK: local/rid; DATA: the 197 tables, local/fv8/data)
set -euo pipefail
WORK=${1:?WORK folder of the fold runs}; DATA=${2:?DATA: the 197 tables}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
STUDIES=$HERE/../../studies
# Both named explicitly: `full` itself became the candidate after the decision.
BUDGETS=("full@schedule=constant,weight_lr=0.003" "full@schedule=cosine,weight_lr=0.01")
read_all() {  # THREADS: the fold runs' readings, then the tables'
    local threads=$1 out=$OUT/t$1
    mkdir -p "$out"
    for fold in 0 1 2; do
        trained_on=()
        for m in $(python "$STUDIES/measured_folds/folds.py" others "$fold"); do trained_on+=("f$fold=$m"); done
        OMP_NUM_THREADS=$threads python "$STUDIES/compare_models.py" --models "$WORK/mf-f$fold-s0" --labels "f$fold" \
            --trained-on "${trained_on[@]}" --measurements ../shared/data/rgl-measured/*.bsdf --budgets "${BUDGETS[@]}" \
            --samples 4000 --draws 3 --resolution 128 --out "$out/f$fold" > "$out/f$fold.log" 2>&1
    done
    OMP_NUM_THREADS=$threads python "$STUDIES/compare_models.py" --models pretrained --labels v9 \
        --held-out "$HERE/../folds-v8/config-v8.json" "$DATA" --budgets "${BUDGETS[@]}" --samples 4000 --draws 3 \
        --resolution 128 --out "$out/tables" > "$out/tables.log" 2>&1
}
read_all 1
read_all 2
