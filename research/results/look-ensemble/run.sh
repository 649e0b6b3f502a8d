#!/usr/bin/env bash
# look-ensemble's judged readings (README.md): new families (seed 20) and the held-out tables 21-40 at once, then the
# measurements; draws 0 and 1.
#
#   bash research/results/look-ensemble/run.sh OUT
set -euo pipefail
OUT=${1:?OUT folder}
HERE=$(dirname "$0")
FAMILIES=local/c4/families20
TABLES=$(python "$HERE/../../studies/split_names.py" held-out "$HERE/../folds-v8/config-v8.json" local/fv8/data 20 40)
mkdir -p "$OUT"
[ -d "$FAMILIES" ] || frenbrdf synth "$FAMILIES" --n 45 --seed 20 --mix families
OMP_NUM_THREADS=1 python "$HERE/read.py" "$FAMILIES"/*.binary --out "$OUT/families" > "$OUT/families.log" 2>&1 &
OMP_NUM_THREADS=1 python "$HERE/read.py" $TABLES --out "$OUT/tables" > "$OUT/tables.log" 2>&1 &
wait
OMP_NUM_THREADS=2 python "$HERE/read.py" ../shared/data/rgl-measured/*.bsdf --out "$OUT/measured" > "$OUT/measured.log" 2>&1
