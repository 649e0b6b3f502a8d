#!/usr/bin/env bash
# The readings of research/results/look-choice (README.md): version 11 (two looks, the last) and eight looks with the
# best-fit choice, encoder alone, 1,500 pairs, draws 0 and 1; the judged sets two at a time, then the measurements.
#
#   bash research/results/look-choice/run.sh OUT
set -euo pipefail
OUT=${1:?OUT folder}
HERE=$(dirname "$0")
READ="python $HERE/../../studies/repeated_look.py"
FAMILIES=local/c4/families19
TABLES=$(python "$HERE/../../studies/split_names.py" held-out "$HERE/../folds-v8/config-v8.json" local/fv8/data 20 40)
mkdir -p "$OUT"
[ -d "$FAMILIES" ] || frenbrdf synth "$FAMILIES" --n 45 --seed 19 --mix families
read_set() {  # $1 name, then the materials
    OMP_NUM_THREADS=1 $READ "${@:2}" --steps 2 --draws 0 1 --out "$OUT/$1/v11" > "$OUT/$1-v11.log" 2>&1
    OMP_NUM_THREADS=1 $READ "${@:2}" --steps 8 --choice best-fit --draws 0 1 --out "$OUT/$1/best8" \
        > "$OUT/$1-best8.log" 2>&1
}
read_set families "$FAMILIES"/*.binary & read_set tables $TABLES & wait
read_set measured ../shared/data/rgl-measured/*.bsdf
