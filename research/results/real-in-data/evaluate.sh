#!/usr/bin/env bash
# The scores of research/results/real-in-data (README.md): the finished `mf` runs (WORK/mf-fF-sS), each on
# the measurements of its own fold (it trained on the others), 4,000 random valid bins (draw 0: folds-v8's draws),
# encoder, `latent` and `full`; and on the 40 held-out tables, encoder and `latent`; two processes, one thread
# each. Then issue 47's table: each measurement through random bins and the five device patterns at 1,500 samples
# (folds-v8's patterns-v8 draws), encoder, `latent`, and `latent` with the coverage weights of `frenbrdf
# reconstruct` (K = 32). decide.py pairs these rows with folds-v8's `v8` rows.
#
#   [ARMS="mf mfd"] bash research/results/real-in-data/evaluate.sh WORK DATA OUT   (ARMS: research/results/diffractive)
#   (DATA the 197 tables the `v8` runs trained on, whose held-out ones are read)
set -euo pipefail
WORK=${1:?WORK folder}; DATA=${2:?DATA folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
COMPARE="python $HERE/../../studies/compare_models.py"
FOLDS="python $HERE/../../studies/measured_folds/folds.py"
models=(); labels=(); trained_on=()
for arm in ${ARMS:-mf}; do  # the first arm is the baseline of the differences
    for run in "$WORK/$arm"-f[012]-s*; do
        grep -q "best epoch" "$run.log" 2> /dev/null || continue  # finished: train.sh's log ends with it
        label=$arm/${run##*/$arm-}; fold=${label#*/f}; fold=${fold%%-*}
        models+=("$run"); labels+=("$label")
        for name in $($FOLDS others "$fold"); do trained_on+=("$label=$name"); done
    done
done
mkdir -p "$OUT"
OMP_NUM_THREADS=1 $COMPARE --models "${models[@]}" --labels "${labels[@]}" --trained-on "${trained_on[@]}" \
    --measurements ../shared/data/rgl-measured/*.bsdf --budgets none latent full --samples 4000 --resolution 128 \
    --group $($FOLDS groups) comparison-four=acrylic_felt_green_rgb,paper_white_rgb,vch_golden_yellow_rgb,cg_sunflower_rgb \
    --out "$OUT/measured" > "$OUT/measured.log" 2>&1 &
OMP_NUM_THREADS=1 $COMPARE --models "${models[@]}" --labels "${labels[@]}" \
    --held-out "$HERE/../folds-v8/config-v8.json" "$DATA" --budgets none latent --samples 4000 --resolution 128 \
    --out "$OUT/tables" > "$OUT/tables.log" 2>&1 &
wait
OMP_NUM_THREADS=1 $COMPARE --models "${models[@]}" --labels "${labels[@]}" --trained-on "${trained_on[@]}" \
    --measurements ../shared/data/rgl-measured/*.bsdf --samples 1500 \
    --patterns merl-bins uniform in-plane gonioreflectometer image-based specular \
    --budgets none latent latent@coverage_k=32 --resolution 128 --group $($FOLDS groups) \
    --out "$OUT/patterns-mf" > "$OUT/patterns-mf.log" 2>&1
