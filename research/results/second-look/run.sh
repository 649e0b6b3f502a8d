#!/usr/bin/env bash
# The runs and readings of research/results/second-look (README.md): seeds 1-3 of the second look, 300 epochs each on
# one thread, all three at once (a seed whose OUT/sS/done exists is not trained again); then each set scored.
#
#   bash research/results/second-look/run.sh OUT
set -euo pipefail
OUT=${1:?OUT folder}
HERE=$(dirname "$0")
LOOK="python $HERE/../../studies/second_look.py"
FAMILIES=local/c4/families16
mkdir -p "$OUT"
train() {
    [ -f "$OUT/s$1/second_look.pt" ] && [ -f "$OUT/s$1/done" ] && return 0
    OMP_NUM_THREADS=1 $LOOK train "$HERE/../folds-v8/config-v8.json" local/fv8/data --out "$OUT/s$1" --minutes 120 \
        --epochs 300 --seed "$1" > "$OUT/s$1.log" 2>&1 && touch "$OUT/s$1/done"
}
train 1 & train 2 & train 3 & wait
[ -d "$FAMILIES" ] || frenbrdf synth "$FAMILIES" --n 45 --seed 16 --mix families
TABLES=$(python -c "import json, sys; print(' '.join(f'local/fv8/data/{n}.binary' for n in json.load(open(sys.argv[1]))['holdout']))" \
    "$HERE/../folds-v8/config-v8.json")
SCORE="--runs $OUT/s1 $OUT/s2 $OUT/s3 --count 1500 --draws 0 1"
OMP_NUM_THREADS=1 $LOOK score "$FAMILIES"/*.binary $SCORE --out "$OUT/families" > "$OUT/families.log" 2>&1 &
OMP_NUM_THREADS=1 $LOOK score $TABLES $SCORE --out "$OUT/tables" > "$OUT/tables.log" 2>&1 &
wait
OMP_NUM_THREADS=2 $LOOK score ../shared/data/rgl-measured/*.bsdf $SCORE --out "$OUT/measured" > "$OUT/measured.log" 2>&1
