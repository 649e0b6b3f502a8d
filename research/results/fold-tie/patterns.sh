#!/usr/bin/env bash
# fold-tie's exploration after the decision (README.md; decides nothing): each measurement through random bins and
# the five device patterns at 1,500 samples (real-in-data's patterns-mf draws) by the ARM (default `mftie`) run of its
# own fold, encoder and `latent`, into OUT/patterns/fF; one process a fold, two at a time. Compared with
# real-in-data's `mf` seed-0 rows by `patterns.py OUT/patterns [ARM]` (research/results/raw-measured's too).
#
#   [ARM=mftie] bash research/results/fold-tie/patterns.sh WORK OUT
set -euo pipefail
WORK=${1:?WORK folder}; OUT=${2:?OUT folder}
HERE=$(dirname "$0"); export ARM=${ARM:-mftie}
mkdir -p "$OUT/patterns"
printf '%s\n' 0 1 2 | OMP_NUM_THREADS=1 xargs -P 2 -I{} bash -c '
    folds="python $0/../../studies/measured_folds/folds.py"; fold=$3; label=$ARM/f$fold-s0
    measurements=(); for name in $($folds fold "$fold"); do measurements+=("../shared/data/rgl-measured/$name.bsdf"); done
    trained_on=(); for name in $($folds others "$fold"); do trained_on+=("$label=$name"); done
    python "$0/../../studies/compare_models.py" --models "$1/$ARM-f$fold-s0" --labels "$label" \
        --trained-on "${trained_on[@]}" --measurements "${measurements[@]}" --samples 1500 \
        --patterns merl-bins uniform in-plane gonioreflectometer image-based specular --budgets none latent \
        --resolution 128 --out "$2/patterns/f$fold" > "$2/patterns/f$fold.log" 2>&1' "$HERE" "$WORK" "$OUT" {}
