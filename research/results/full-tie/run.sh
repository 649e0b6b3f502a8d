#!/usr/bin/env bash
# The full-tie study's readings (README.md), one process at a time: the 19 measurements and the 40 held-out tables by
# compare_models.py, the seam step on the 19, and the time.
#
#   bash research/results/full-tie/run.sh TABLES OUT
set -euo pipefail
TABLES=${1:?tables folder}; OUT=${2:?OUT folder}
HERE=$(dirname "$0"); STUDIES=$HERE/../../studies
MEASURED=(../shared/data/rgl-measured/*.bsdf)
budgets=(--budgets full full@tie=0.1)
mkdir -p "$OUT"
export OMP_NUM_THREADS=1
python "$STUDIES/compare_models.py" --models pretrained --labels v12 "${budgets[@]}" --samples 4000 --resolution 128 \
    --measurements "${MEASURED[@]}" --out "$OUT/measured" > "$OUT/measured.log" 2>&1
python "$STUDIES/compare_models.py" --models pretrained --labels v12 "${budgets[@]}" --samples 4000 --resolution 128 \
    --held-out release/shipped_model.json "$TABLES" --out "$OUT/tables" > "$OUT/tables.log" 2>&1
python "$STUDIES/seam.py" "${MEASURED[@]}" --budgets full full@tie=0.1 --json "$OUT/seam.json" > "$OUT/seam.log" 2>&1
unset OMP_NUM_THREADS  # the time as a user's process takes it: torch's and the native core's default threads
python "$HERE/timing.py" "${MEASURED[@]}" --tie 0.1 > "$OUT/timing.txt"
python "$HERE/decide.py" "$OUT" | tee "$OUT/decision.txt"
