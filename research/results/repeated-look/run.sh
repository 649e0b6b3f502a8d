#!/usr/bin/env bash
# The readings of research/results/repeated-look (README.md): the package model (version 10) with 1 and 2 looks,
# encoder alone, 1,500 pairs through random bins and the five devices, draws 0 and 1; the judged sets two at a time
# on the two cores, then the sets reported only.
#
#   bash research/results/repeated-look/run.sh OUT
set -euo pipefail
OUT=${1:?OUT folder}
HERE=$(dirname "$0")
READ="python $HERE/../../studies/repeated_look.py"
OPTIONS="--steps 1 2 --draws 0 1"
FAMILIES=local/c4/families17
HOLDOUT="$HERE/../folds-v8/config-v8.json"
tables() {  # the held-out tables $1 … $2 of folds-v8's list
    python "$HERE/../../studies/split_names.py" held-out "$HOLDOUT" local/fv8/data "$1" "$2"
}
mkdir -p "$OUT"
[ -d "$FAMILIES" ] || frenbrdf synth "$FAMILIES" --n 45 --seed 17 --mix families
OMP_NUM_THREADS=1 $READ "$FAMILIES"/*.binary --out "$OUT/families" $OPTIONS > "$OUT/families.log" 2>&1 &
OMP_NUM_THREADS=1 $READ $(tables 20 40) --out "$OUT/tables" $OPTIONS > "$OUT/tables.log" 2>&1 &
wait
OMP_NUM_THREADS=1 $READ $(tables 0 20) --out "$OUT/tables-seen" $OPTIONS > "$OUT/tables-seen.log" 2>&1 &
OMP_NUM_THREADS=1 $READ ../shared/data/rgl-measured/*.bsdf --out "$OUT/measured" $OPTIONS > "$OUT/measured.log" 2>&1 &
wait
