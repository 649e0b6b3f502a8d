#!/usr/bin/env bash
# fold-tie's readings (README.md) of the runs WORK/mftie-fF-s0 into OUT: the 19 by the run of their own fold (encoder,
# `latent`, `full`), the 40 held-out tables (encoder, `latent`), each fold's seam steps; then the rule (decide.py).
#
#   bash research/results/fold-tie/read.sh DATA WORK OUT   (DATA: the 197 tables the runs trained on)
set -euo pipefail
DATA=${1:?DATA folder}; WORK=${2:?WORK folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0"); STUDIES=$HERE/../../studies
RUNS=("$WORK"/mftie-f{0,1,2}-s0)
bash "$HERE/../real-in-data/score_runs.sh" "$OUT" "${RUNS[@]}"
bash "$HERE/../latent-size/score_tables.sh" "$DATA" "$OUT" "${RUNS[@]}" &
tables=$!
for fold in 0 1 2; do
    measurements=(); for name in $(python "$STUDIES/measured_folds/folds.py" fold "$fold"); do
        measurements+=("../shared/data/rgl-measured/$name.bsdf"); done
    OMP_NUM_THREADS=1 python "$STUDIES/seam.py" "${measurements[@]}" --model "$WORK/mftie-f$fold-s0" \
        --json "$OUT/seam-f$fold.json" > "$OUT/seam-f$fold.log" 2>&1
done
wait "$tables"  # a failed reading of the tables stops here, before decide.py
python "$HERE/decide.py" "$OUT" | tee "$OUT/decide.txt"
