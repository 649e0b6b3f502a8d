#!/usr/bin/env bash
# The sampling-patterns study's trainings (research/results/sampling-patterns): six variants, two or three seeds, on
# the study's folders, the same 39 held-out tables (the configs' `holdout`: seed 0's test split), 150 epochs each,
# two at a time on one thread each. The data: the MERL fits, the default bank, and the RGL fits other than
# the 19 real measurements' (so that none of ../shared/data/rgl-measured was trained on by any run).
#
#   bash research/studies/sampling_patterns/train.sh DATA WORK
set -euo pipefail
DATA=${1:?DATA folder}; WORK=${2:?WORK folder}
HERE=$(dirname "$0")
# The runs made (the README says why some variants have two seeds): VARIANT SEED per line.
RUNS="paper-mean 0;paper-mean 1;paper-mean 2;instruments-mean 0;instruments-mean 1;instruments-mean 2
instruments-density 0;instruments-density 1;mixed-mean 0;mixed-mean 1;mixed-density 0;mixed-density 1
paper-density 0;paper-density 1"
tr ';' '\n' <<< "$RUNS" | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c \
    'frenbrdf train --data "$0" --config "$1/$3.json" --seed "$4" --out "$2/$3-s$4" --quiet > "$2/$3-s$4.log" 2>&1' \
    "$DATA" "$HERE" "$WORK"
