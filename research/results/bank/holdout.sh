#!/bin/bash
# Leave a family out: every method trained on the bank without its 10 fabrics (the held-out test
# split, --holdout), three seeds, then evaluated on the fabrics.
# Usage: research/results/bank/holdout.sh [FOLDER]   (default bank-holdout)
set -e
mkdir -p "${1:-bank-holdout}" && cd "${1:-bank-holdout}"
export OMP_NUM_THREADS=1
start=$(date +%s)
[ -f bank/bank.json ] || frenbrdf synth bank --quiet
for m in frenbrdf nbrdf hyperbrdf; do
  t=$(date +%s)
  frenbrdf train --method $m --training demo --data bank --holdout '*fabric*' --out runs/$m --seeds 0 1 2 --quiet --json
  echo "train $m (seeds 0 1 2) $(( $(date +%s) - t )) s"
done
t=$(date +%s)
frenbrdf evaluate runs/*/seed-* --out eval-fabrics --quick --refine latent --quiet
echo "evaluate $(( $(date +%s) - t )) s"
echo "total $(( $(date +%s) - start )) s"
