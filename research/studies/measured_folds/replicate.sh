#!/usr/bin/env bash
# The replication of the fold study's hypothesis (research/results/measured-folds, "Replication"): the measurements
# and the families together (`families`) against neither (`fits`), on seeds no earlier run used. Each fold's data
# with the measurements of the two other folds and the families is train_families.sh's (linked from OLDWORK);
# `fits` trains on DATA alone. Seeds 3 and 4 for `fits` (0-2 exist), 2 and 3 for `families` (0-1 exist), two at a
# time on one thread each (JOBS: how many at a time).
#
#   bash research/studies/measured_folds/replicate.sh DATA CONFIG OLDWORK WORK
set -euo pipefail
DATA=${1:?DATA folder}; CONFIG=${2:?CONFIG json}; OLDWORK=${3:?train.sh WORK folder}; WORK=${4:?new WORK folder}
source "$(dirname "$0")/../../../release/link_inputs.sh"
mkdir -p "$WORK"
for fold in 0 1 2; do link_into "$WORK" "$OLDWORK/data-f$fold-families"; done
# One run per line: the data folder, the seed, the run's name.
{
    for seed in 3 4; do echo "$DATA $seed fits-s$seed"; done
    for seed in 2 3; do for fold in 0 1 2; do echo "$WORK/data-f$fold-families $seed families-f$fold-s$seed"; done; done
} | OMP_NUM_THREADS=1 xargs -P "${JOBS:-2}" -L 1 bash -c \
    'frenbrdf train --data "$2" --config "$0" --seed "$3" --out "$1/$4" --quiet > "$1/$4.log" 2>&1' \
    "$CONFIG" "$WORK"
