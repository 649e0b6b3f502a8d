#!/bin/bash
# Full protocol on the 80 MERL-derived materials (published NBRDF fits evaluated at every bin),
# one run per method and seed (each seed its own 70/10/20 split and initialisation).
# Usage: [SEEDS="0 1 2"] docs/results/merl/run.sh [FOLDER]   (default merl-protocol; ../shared beside the repository)
set -e
seeds=${SEEDS:-0 1 2}
shared=$(cd "$(dirname "$0")/../../../../shared" && pwd)
mkdir -p "${1:-merl-protocol}" && cd "${1:-merl-protocol}"
start=$(date +%s)
frenbrdf import-nbrdf "$shared"/data/merl-nbrdf/*.h5 merl --quiet
echo "import $(( $(date +%s) - start )) s"
for m in frenbrdf nbrdf hyperbrdf; do
  t=$(date +%s)
  frenbrdf train --method $m --data merl --out runs-merl/$m --seeds $seeds --quiet --json
  echo "train $m (seeds $seeds) $(( $(date +%s) - t )) s"
done
t=$(date +%s)
frenbrdf evaluate runs-merl/*/seed-* --out eval-merl --quick --quiet
echo "evaluate $(( $(date +%s) - t )) s"
echo "total $(( $(date +%s) - start )) s"
