#!/bin/bash
# Full protocol on the 80 MERL-derived materials (published NBRDF fits evaluated at every bin).
# Usage: docs/results/merl/run.sh [FOLDER]   (default merl-protocol; ../shared beside the repository)
set -e
shared=$(cd "$(dirname "$0")/../../../../shared" && pwd)
mkdir -p "${1:-merl-protocol}" && cd "${1:-merl-protocol}"
start=$(date +%s)
frenbrdf import-nbrdf "$shared"/data/merl-nbrdf/*.h5 merl --quiet
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
