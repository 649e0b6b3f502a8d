#!/usr/bin/env bash
# latent-size's reading of the 40 held-out tables (README.md): the runs given, encoder and `latent`, 4,000 random
# valid bins, as real-in-data's evaluate.sh read `mf`'s seed-0 runs; one process, one thread.
#
#   bash research/results/latent-size/score_tables.sh DATA OUT RUN...   (DATA: the 197 tables the runs trained on)
set -euo pipefail
DATA=${1:?DATA folder}; OUT=${2:?OUT folder}; shift 2
HERE=$(dirname "$0")
models=(); labels=()
for run in "$@"; do
    grep -q "best epoch" "$run.log" || { echo "error: $run has not finished (its log has no best epoch)" >&2; exit 1; }
    name=${run##*/}; arm=${name%%-f*}
    models+=("$run"); labels+=("$arm/${name#"$arm"-}")
done
mkdir -p "$OUT"
OMP_NUM_THREADS=1 python "$HERE/../../studies/compare_models.py" --models "${models[@]}" --labels "${labels[@]}" \
    --held-out "$HERE/../folds-v8/config-v8.json" "$DATA" --budgets none latent --samples 4000 --resolution 128 \
    --out "$OUT/tables" > "$OUT/tables.log" 2>&1
