#!/bin/bash
# Full protocol on the 80 MERL-derived materials (published NBRDF fits evaluated at every bin),
# three seeds per method (each its own 70/10/20 split and initialisation).
# Usage: docs/results/merl/run.sh [FOLDER]   (default merl-protocol; ../shared beside the repository)
set -e
shared=$(cd "$(dirname "$0")/../../../../shared" && pwd)
mkdir -p "${1:-merl-protocol}" && cd "${1:-merl-protocol}"
start=$(date +%s)
frenbrdf import-nbrdf "$shared"/data/merl-nbrdf/*.h5 merl --quiet
echo "import $(( $(date +%s) - start )) s"
for m in frenbrdf nbrdf hyperbrdf; do
  t=$(date +%s)
  frenbrdf train --method $m --data merl --out runs-merl/$m --seeds 0 1 2 --quiet --json
  echo "train $m (3 seeds) $(( $(date +%s) - t )) s"
done
t=$(date +%s)
frenbrdf evaluate runs-merl/*/seed-* --out eval-merl --quiet
echo "evaluate $(( $(date +%s) - t )) s"
echo "total $(( $(date +%s) - start )) s"
