#!/usr/bin/env bash
# decoder-finetune's fifth amendment (README.md): the augmented kept-encoder fit on the shipped recipe's fold runs.
# Each stage is skipped where its output is complete, so the script continues where an earlier call stopped.
#   1. the shipped recipe (folds-v8/config-v8.json) trained per fold, seed 0, as real-in-data's `mf` runs:
#      WORK/mf-fF-s0 (three at once, one thread each; about 70 minutes on a 2-core CPU);
#   2. each fitted from seeds 0 and 1: FT/augment-fF and FT/s1/augment-fF (three at once; about 18 minutes a seed);
#   3. both read on draw 2 against the base (run.sh) and judged pooled over the two seeds (decide.py).
#
#   bash research/results/decoder-finetune/recipe.sh DATA FAMILIES WORK FT OUT
# (DATA: the 197 tables, e.g. local/fv8/data; FAMILIES: local/c4/families0; WORK: local/rid; FT: local/dft/mf)
set -euo pipefail
DATA=${1:?DATA: the 197 tables}; FAMILIES=${2:?FAMILIES bank}; WORK=${3:?WORK folder}; FT=${4:?FT folder}
OUT=${5:?OUT folder}
HERE=$(dirname "$0")
# A training has finished when its log names its best epoch; one stopped midway (its last.pt there) continues.
fresh=""; stopped=""
for fold in 0 1 2; do
    grep -qs "best epoch" "$WORK/mf-f$fold-s0.log" && continue
    if [[ -f $WORK/mf-f$fold-s0/last.pt ]]; then stopped+="$fold "; else fresh+="$fold "; fi
done
train() {  # FOLDS, and RESUME=1 to continue them
    FOLDS=$1 RESUME=$2 ARM=mf CONFIG=$HERE/../folds-v8/config-v8.json \
        bash "$HERE/../real-in-data/train.sh" "$DATA" "$FAMILIES" "$WORK"
}
[[ -z $fresh ]] || train "$fresh" ""
[[ -z $stopped ]] || train "$stopped" 1
for seed in 0 1; do
    dest=$FT; [[ $seed == 0 ]] || dest=$FT/s$seed
    mkdir -p "$dest"
    for fold in 0 1 2; do
        [[ -f $dest/augment-f$fold/best.pt ]] && continue
        echo "$fold"
    done | OMP_NUM_THREADS=1 xargs -r -P 3 -I{} bash -c 'frenbrdf fit-decoder "$0/mf-f$1-s0" --out "$2/augment-f$1" \
        --encoder-weight 1 --encoder-lr 0 --encoder-augment --seed "$3" --quiet > "$2/augment-f$1.log" 2>&1' \
        "$WORK" {} "$dest" "$seed"
done
for seed in 0 1; do
    dest=$FT; [[ $seed == 0 ]] || dest=$FT/s$seed
    [[ -f $OUT/seed$seed/tables/compare.json ]] || \
        BASE=mf DRAW=2 ARM=augment bash "$HERE/run.sh" "$WORK" "$dest" "$DATA" "$OUT/seed$seed"
done
python "$HERE/decide.py" "$OUT/seed0" "$OUT/seed1" --arm augment --encoder-rule --to "$OUT" | tee "$OUT/decide.txt"
