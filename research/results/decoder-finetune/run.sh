#!/usr/bin/env bash
# decoder-finetune's judging runs (README.md): each fold's base run WORK/mfw512-fF-s0 and its fine-tuned copy
# FT/ft-fF read on the measurements it did not train on (4,000 random bins, draw 0, encoder, `latent`, `full`,
# 128²), one process a fold, two at a time; then all six on the 40 held-out tables of DATA (encoder, `latent`).
#
#   [ARM=ft] bash research/results/decoder-finetune/run.sh WORK FT DATA OUT
# ARM=refit reads the amendment's runs FT/refit-fF (the fine-tuned decoders with their encoders trained again);
# ARM=joint the second amendment's FT/joint-fF (the encoder fitted with the decoder). DRAW=1 reads other random bins
# (the fourth amendment's judging draw; default 0). BASE=mf reads WORK/mf-fF-s0 as the base runs (the fifth
# amendment's: the shipped recipe's; default mfw512).
set -euo pipefail
WORK=${1:?WORK folder of the base runs}; FT=${2:?folder of the fine-tuned runs}; DATA=${3:?DATA: the 197 tables}
OUT=${4:?OUT folder}
HERE=$(dirname "$0")
export ARM=${ARM:-ft} DRAW=${DRAW:-0} BASE=${BASE:-mfw512}
STUDIES=$HERE/../../studies
mkdir -p "$OUT"
for fold in 0 1 2; do echo "$fold"; done | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c '
    work=$1; ft=$2; out=$3; fold=$4; trained_on=()
    for m in $(python "$0/measured_folds/folds.py" others "$fold"); do trained_on+=("base/f$fold=$m" "$ARM/f$fold=$m"); done
    python "$0/compare_models.py" --models "$work/$BASE-f$fold-s0" "$ft/$ARM-f$fold" --labels "base/f$fold" "$ARM/f$fold" \
        --trained-on "${trained_on[@]}" --measurements ../shared/data/rgl-measured/*.bsdf --budgets none latent full \
        --samples 4000 --draws $DRAW --resolution 128 --group $(python "$0/measured_folds/folds.py" groups) \
        --out "$out/f$fold" > "$out/f$fold.log" 2>&1' "$STUDIES" "$WORK" "$FT" "$OUT"
models=(); labels=()
for arm in base "$ARM"; do for fold in 0 1 2; do
    [[ $arm == base ]] && models+=("$WORK/$BASE-f$fold-s0") || models+=("$FT/$arm-f$fold")
    labels+=("$arm/f$fold")
done; done
OMP_NUM_THREADS=2 python "$STUDIES/compare_models.py" --models "${models[@]}" --labels "${labels[@]}" \
    --held-out "$HERE/../folds-v8/config-v8.json" "$DATA" --budgets none latent --samples 4000 --draws $DRAW --resolution 128 \
    --out "$OUT/tables" > "$OUT/tables.log" 2>&1
