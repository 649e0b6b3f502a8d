#!/usr/bin/env bash
# latent-rate's exploration (README.md; decides only which rate is judged): the shipped model's `latent` at four
# starting rates (600 steps, cosine), from 4,000 random bins and through the five device patterns at 1,500, on 15
# families of a seed never read before (22) and the held-out tables 1-20. Two processes, one thread each.
#
#   bash research/results/latent-rate/explore.sh OUT
set -euo pipefail
OUT=${1:?OUT folder}
HERE=$(dirname "$0")
FAMILIES=local/c4/families22
TABLES=$(python "$HERE/../../studies/split_names.py" held-out "$HERE/../folds-v8/config-v8.json" local/fv8/data 0 20)
[ -d "$FAMILIES" ] || frenbrdf synth "$FAMILIES" --n 15 --seed 22 --mix families
budgets=(--budgets latent latent@latent_lr=0.015 latent@latent_lr=0.06 latent@latent_lr=0.1)
read_set() {  # NAME, then the materials
    local name=$1; shift
    for reading in "random --samples 4000" "devices --patterns uniform in-plane gonioreflectometer image-based specular --samples 1500"; do
        local kind=${reading%% *} how=${reading#* }
        [[ -f "$OUT/$name-$kind/compare.json" ]] && continue
        # shellcheck disable=SC2086
        OMP_NUM_THREADS=1 python "$HERE/../../studies/compare_models.py" --resolution 128 --models pretrained \
            --labels v12 "${budgets[@]}" --tables "$@" $how --out "$OUT/$name-$kind" > "$OUT/$name-$kind.log" 2>&1
    done
}
mkdir -p "$OUT"
read_set families "$FAMILIES"/*.binary &
# shellcheck disable=SC2086
read_set tables $TABLES &
wait
