#!/bin/bash
# Full protocol on the 80 MERL-derived materials (published NBRDF fits evaluated at every bin).
set -e
cd /work/protocol
start=$(date +%s)
frenbrdf import-nbrdf /work/shared/data/merl-nbrdf/*.h5 merl --quiet
echo "import $(( $(date +%s) - start )) s"
for m in frenbrdf nbrdf hyperbrdf; do
  t=$(date +%s)
  frenbrdf train --method $m --data merl --out runs-merl/$m --quiet --json
  echo "train $m $(( $(date +%s) - t )) s"
done
t=$(date +%s)
frenbrdf evaluate runs-merl/frenbrdf runs-merl/nbrdf runs-merl/hyperbrdf --out eval-merl --quiet --json
echo "evaluate $(( $(date +%s) - t )) s"
echo "total $(( $(date +%s) - start )) s"
