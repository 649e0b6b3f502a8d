#!/usr/bin/env bash
# raw-measured's readings (README.md) of the runs WORK/ARM-fF-s0 (ARM default mfraw; more-measured's mfmore) into OUT:
# the 19 by the run of their own fold (encoder, `latent`, `full`) and the 40 held-out tables (encoder, `latent`), at
# once; then the rule (decide.py).
#
#   [ARM=mfraw] bash research/results/raw-measured/read.sh DATA WORK OUT   (DATA: the 197 tables the runs trained on)
set -euo pipefail
DATA=${1:?DATA folder}; WORK=${2:?WORK folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
ARM=${ARM:-mfraw}
RUNS=("$WORK/$ARM"-f{0,1,2}-s0)
bash "$HERE/../latent-size/score_tables.sh" "$DATA" "$OUT" "${RUNS[@]}" &
tables=$!
bash "$HERE/../real-in-data/score_runs.sh" "$OUT" "${RUNS[@]}"
wait "$tables"  # a failed reading of the tables stops here, before decide.py
python "$HERE/decide.py" "$OUT" --arm "$ARM" | tee "$OUT/decide.txt"
