#!/bin/bash
# The default bank (100 analytic materials): the demo (seed 0), two more seeds of the demo's
# training, then the full evaluation protocol over the three seeds.
# Usage: docs/results/bank/run.sh [FOLDER]   (default bank-protocol)
set -e
mkdir -p "${1:-bank-protocol}" && cd "${1:-bank-protocol}"
start=$(date +%s)
frenbrdf demo --out demo --quiet
echo "demo $(( $(date +%s) - start )) s"
for m in frenbrdf nbrdf hyperbrdf; do
  t=$(date +%s)
  frenbrdf train --method $m --training demo --data demo/data --out bank/$m --seeds 1 2 --quiet --json
  echo "train $m (seeds 1, 2) $(( $(date +%s) - t )) s"
done
t=$(date +%s)
frenbrdf evaluate demo/runs/* bank/*/seed-* --out eval-bank --quick --quiet
echo "evaluate $(( $(date +%s) - t )) s"
echo "total $(( $(date +%s) - start )) s"
