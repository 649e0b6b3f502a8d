#!/usr/bin/env bash
# The readings of research/results/encoder-choice (README.md): version 9's encoders through the five device patterns
# on 45 new families (seed 15) and the 40 held-out tables, and the 19 measurements (reported only). One thread each,
# the families and the tables at once, then the measurements.
#
#   bash research/results/encoder-choice/run.sh DATA OUT   (DATA: the 197 tables, local/fv8/data)
set -euo pipefail
DATA=${1:?DATA folder}; OUT=${2:?OUT folder}
HERE=$(dirname "$0")
CHOICE="python $HERE/../../studies/encoder_choice.py"
OPTIONS="--patterns uniform in-plane gonioreflectometer image-based specular --count 1500 --draws 0 1"
FAMILIES=local/c4/families15
mkdir -p "$OUT"
[ -d "$FAMILIES" ] || frenbrdf synth "$FAMILIES" --n 45 --seed 15 --mix families
TABLES=$(python -c "import json, sys; print(' '.join(f'{sys.argv[2]}/{n}.binary' for n in json.load(open(sys.argv[1]))['holdout']))" \
    "$HERE/../folds-v8/config-v8.json" "$DATA")
OMP_NUM_THREADS=1 $CHOICE "$FAMILIES"/*.binary $OPTIONS --out "$OUT/families" > "$OUT/families.log" 2>&1 &
OMP_NUM_THREADS=1 $CHOICE $TABLES $OPTIONS --out "$OUT/tables" > "$OUT/tables.log" 2>&1 &
wait
OMP_NUM_THREADS=2 $CHOICE ../shared/data/rgl-measured/*.bsdf $OPTIONS --out "$OUT/measured" > "$OUT/measured.log" 2>&1
