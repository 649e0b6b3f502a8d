#!/usr/bin/env bash
# latent-rate's judged readings (README.md): `latent` at 3e-2 and at the candidate RATE (600 steps, cosine), from
# 4,000 random bins (OUT/*-random) and through the five device patterns at 1,500 (OUT/*-devices): the shipped model
# on 45 new families (seed 23) and the held-out tables 21-40, two processes at once; then the 19 real measurements,
# each by the fold run of RUNS (real-in-data's WORK: mf-f0-s0, mf-f1-s0, mf-f2-s0) that did not train on it, from
# 4,000 random bins (OUT/measured). A rerun goes on where the last stopped.
#
#   bash research/results/latent-rate/run.sh RATE RUNS OUT
set -euo pipefail
RATE=${1:?candidate rate}; RUNS=${2:?fold runs folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
FAMILIES=local/c4/families23
TABLES=$(python -c "import json, sys; print(' '.join(f'local/fv8/data/{n}.binary' for n in json.load(open(sys.argv[1]))['holdout'][20:40]))" \
    "$HERE/../folds-v8/config-v8.json")
folds="python $HERE/../../studies/measured_folds/folds.py"
budgets=(--budgets latent "latent@latent_lr=$RATE")
devices=(--patterns uniform in-plane gonioreflectometer image-based specular --samples 1500)
compare() {  # NAME, then the models, the materials and what reads them
    local name=$1; shift
    [[ -f "$OUT/$name/compare.json" ]] && return 0
    OMP_NUM_THREADS=1 python "$HERE/../../studies/compare_models.py" --resolution 128 --out "$OUT/$name" "$@" \
        > "$OUT/$name.log" 2>&1 || { echo "$name failed: $OUT/$name.log" >&2; exit 1; }
}
[ -d "$FAMILIES" ] || frenbrdf synth "$FAMILIES" --n 45 --seed 23 --mix families
mkdir -p "$OUT"
shipped=(--models pretrained --labels v12 "${budgets[@]}")
# shellcheck disable=SC2086
{ compare families-random "${shipped[@]}" --tables "$FAMILIES"/*.binary --samples 4000
  compare families-devices "${shipped[@]}" --tables "$FAMILIES"/*.binary "${devices[@]}"; } &
# shellcheck disable=SC2086
{ compare tables-random "${shipped[@]}" --tables $TABLES --samples 4000
  compare tables-devices "${shipped[@]}" --tables $TABLES "${devices[@]}"; } &
wait
for run in "$RUNS"/mf-f{0,1,2}-s0; do
    grep -q "best epoch" "$run.log" || { echo "$run has not finished (its log has no best epoch)" >&2; exit 1; }
done
trained_on=()
for fold in 0 1 2; do for m in $($folds others "$fold"); do trained_on+=("mf/f$fold=$m"); done; done
compare measured --models "$RUNS"/mf-f0-s0 "$RUNS"/mf-f1-s0 "$RUNS"/mf-f2-s0 --labels mf/f0 mf/f1 mf/f2 \
    --trained-on "${trained_on[@]}" --measurements ../shared/data/rgl-measured/*.bsdf --samples 4000 \
    --budgets none latent "latent@latent_lr=$RATE" --group $($folds groups)
python "$HERE/decide.py" judge "$OUT" "$RATE" > "$OUT/decision.txt"
cat "$OUT/decision.txt"
