#!/usr/bin/env bash
# The latent-native study's readings (README.md): `latent` at today's 600 steps and at 1,200, from 4,000 random bins
# (OUT/*-random) and through the five device patterns at 1,500 (OUT/*-devices): the shipped model on FAMILIES (the
# judging set) and on its 40 held-out tables (TABLES: a folder holding them as NAME.binary); then the 19 real
# measurements, each by the fold run of RUNS (real-in-data's WORK: mf-f0-s0, mf-f1-s0, mf-f2-s0) that did not
# train on it, from 4,000 random bins (OUT/measured), with the encoder alone too. One process at a time.
#
#   bash research/results/latent-native/run.sh FAMILIES TABLES RUNS OUT
set -euo pipefail
FAMILIES=${1:?families folder}; TABLES=${2:?tables folder}; RUNS=${3:?fold runs folder}; OUT=${4:?OUT folder}
HERE=$(dirname "$0")
folds="python $HERE/../../studies/measured_folds/folds.py"
budgets=(--budgets latent latent@latent_steps=1200)
devices=(--patterns uniform in-plane gonioreflectometer image-based specular --samples 1500)
compare() {  # NAME, then the models, the materials and what reads them
    local name=$1; shift
    [[ -f "$OUT/$name/compare.json" ]] && return 0  # a rerun goes on where the last stopped
    OMP_NUM_THREADS=1 python "$HERE/../../studies/compare_models.py" --resolution 128 --out "$OUT/$name" "$@" \
        > "$OUT/$name.log" 2>&1 || { echo "$name failed: $OUT/$name.log" >&2; exit 1; }
}
mkdir -p "$OUT"
shipped=(--models pretrained --labels v12)
compare families-random "${shipped[@]}" "${budgets[@]}" --tables "$FAMILIES"/*.binary --samples 4000
compare families-devices "${shipped[@]}" "${budgets[@]}" --tables "$FAMILIES"/*.binary "${devices[@]}"
compare tables-random "${shipped[@]}" "${budgets[@]}" --held-out release/shipped_model.json "$TABLES" --samples 4000
compare tables-devices "${shipped[@]}" "${budgets[@]}" --held-out release/shipped_model.json "$TABLES" "${devices[@]}"
for run in "$RUNS"/mf-f{0,1,2}-s0; do
    grep -q "best epoch" "$run.log" || { echo "$run has not finished (its log has no best epoch)" >&2; exit 1; }
done
trained_on=()
for fold in 0 1 2; do for m in $($folds others "$fold"); do trained_on+=("mf/f$fold=$m"); done; done
compare measured --models "$RUNS"/mf-f0-s0 "$RUNS"/mf-f1-s0 "$RUNS"/mf-f2-s0 --labels mf/f0 mf/f1 mf/f2 \
    --trained-on "${trained_on[@]}" --measurements ../shared/data/rgl-measured/*.bsdf --samples 4000 \
    --budgets none latent latent@latent_steps=1200 --group $($folds groups)
python "$HERE/decide.py" "$OUT" > "$OUT/decision.txt"
cat "$OUT/decision.txt"
