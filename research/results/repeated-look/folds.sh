#!/usr/bin/env bash
# repeated-look's fold reading (README.md; reported only): the shipped recipe's seed-0 fold runs (RUNS/mf-fF-s0) with
# the looks second-look trained for them (LOOKS/look-fF), 1 and 2 looks, on each fold's measurements (which neither
# the run nor its look trained on): 4,000 random bins, draw 4 (not read before), encoder and `latent`.
#
#   bash research/results/repeated-look/folds.sh RUNS LOOKS OUT   (RUNS: local/rid, LOOKS: local/slf)
set -euo pipefail
RUNS=${1:?RUNS folder}; LOOKS=${2:?LOOKS folder}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
mkdir -p "$OUT"
for fold in 0 1 2; do
    MEASURED=$(python -c "import json, sys; print(' '.join(f'../shared/data/rgl-measured/{n}.bsdf' for n in json.load(open(sys.argv[1]))['folds'][int(sys.argv[2])]))" \
        "$HERE/../../studies/measured_folds/folds.json" "$fold")
    OMP_NUM_THREADS=2 python "$HERE/../../studies/repeated_look.py" $MEASURED --base "$RUNS/mf-f$fold-s0" \
        --look "$LOOKS/look-f$fold" --steps 1 2 --patterns merl-bins --count 4000 --draws 4 --budgets none latent \
        --out "$OUT/fold$fold" > "$OUT/fold$fold.log" 2>&1
done
