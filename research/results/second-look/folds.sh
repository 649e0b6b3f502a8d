#!/usr/bin/env bash
# second-look's fold reading (README.md, amendment 2): a second look for each of the shipped recipe's seed-0 fold
# runs (RUNS/mf-fF-s0, trained on RUNS/data-mf-fF, which holds no measurement of fold F), 300 epochs, seed 1, the
# three at once; then each fold's measurements, 4,000 random bins, draw 3, encoder, `latent` and `full`, by the
# run alone and with its look.
#
#   bash research/results/second-look/folds.sh RUNS OUT   (RUNS: local/rid)
set -euo pipefail
RUNS=${1:?RUNS folder}; OUT=${2:?OUT folder}
HERE=$(dirname "$0")
LOOK="python $HERE/../../studies/second_look.py"
mkdir -p "$OUT"
for fold in 0 1 2; do
    [ -f "$OUT/look-f$fold/done" ] && continue
    (OMP_NUM_THREADS=1 $LOOK train "$RUNS/mf-f$fold-s0/config.json" "$RUNS/data-mf-f$fold" --base "$RUNS/mf-f$fold-s0" \
        --out "$OUT/look-f$fold" --epochs 300 --minutes 600 --seed 1 --quiet > "$OUT/look-f$fold.log" 2>&1 \
        && touch "$OUT/look-f$fold/done") &
done
wait
for fold in 0 1 2; do
    MEASURED=$(python -c "import json, sys; print(' '.join(f'../shared/data/rgl-measured/{n}.bsdf' for n in json.load(open(sys.argv[1]))['folds'][int(sys.argv[2])]))" \
        "$HERE/../../studies/measured_folds/folds.json" "$fold")
    OMP_NUM_THREADS=2 $LOOK refine $MEASURED --base "$RUNS/mf-f$fold-s0" --runs "$OUT/look-f$fold" --draws 3 \
        --out "$OUT/fold$fold" > "$OUT/fold$fold.log" 2>&1
done
