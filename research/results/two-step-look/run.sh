#!/usr/bin/env bash
# The runs and readings of research/results/two-step-look (README.md): three looks trained on from second-look's s1
# with two looks unrolled, 120 epochs each, all at once on one thread each (a seed whose OUT/sS/done exists is not
# trained again); then version 11 and each run, two looks, on the judged sets and the measurements.
#
#   bash research/results/two-step-look/run.sh OUT
set -euo pipefail
OUT=${1:?OUT folder}
HERE=$(dirname "$0")
STUDIES="$HERE/../../studies"
FAMILIES=local/c4/families18
mkdir -p "$OUT"
train() {
    [ -f "$OUT/s$1/done" ] && return 0
    OMP_NUM_THREADS=1 python "$STUDIES/second_look.py" train "$HERE/../folds-v8/config-v8.json" local/fv8/data \
        --base local/v9pack --init local/sl/judge/s1 --steps 2 --out "$OUT/s$1" --minutes 600 --epochs 120 \
        --seed "$1" --quiet > "$OUT/s$1.log" 2>&1 && touch "$OUT/s$1/done"
}
train 1 & train 2 & train 3 & wait
[ -d "$FAMILIES" ] || frenbrdf synth "$FAMILIES" --n 45 --seed 18 --mix families
TABLES=$(python "$HERE/../../studies/split_names.py" held-out "$HERE/../folds-v8/config-v8.json" local/fv8/data 20 40)
read_set() {  # $1 name, $2 label, then the model options; the materials from $MATERIALS
    OMP_NUM_THREADS=1 python "$STUDIES/repeated_look.py" $MATERIALS --steps 2 --draws 0 1 "${@:3}" \
        --out "$OUT/$1/$2" > "$OUT/$1-$2.log" 2>&1
}
for set in families tables measured; do
    case $set in
        families) MATERIALS="$FAMILIES/*.binary" ;;
        tables) MATERIALS=$TABLES ;;
        measured) MATERIALS="../shared/data/rgl-measured/*.bsdf" ;;
    esac
    read_set "$set" v11 --base pretrained & read_set "$set" s1 --base local/v9pack --look "$OUT/s1" & wait
    read_set "$set" s2 --base local/v9pack --look "$OUT/s2" & read_set "$set" s3 --base local/v9pack --look "$OUT/s3" & wait
done
