#!/bin/bash
# The 80 MERL-derived materials (published NBRDF fits evaluated at every bin): every method at the
# demo's length over three seeds (each its own 70/10/20 split and initialisation), evaluated on
# each seed's test split and on the analytic bank none of them saw (out of distribution).
# Usage: [SEEDS="0 1 2"] research/results/merl/run.sh [FOLDER]   (default merl-protocol; ../shared beside the repository)
set -e
seeds=${SEEDS:-0 1 2}
shared=$(cd "$(dirname "$0")/../../../../shared" && pwd)
mkdir -p "${1:-merl-protocol}" && cd "${1:-merl-protocol}"
export OMP_NUM_THREADS=1
start=$(date +%s)
[ -d merl ] || frenbrdf import-nbrdf "$shared"/data/merl-nbrdf/*.h5 merl --quiet
[ -f bank/bank.json ] || frenbrdf synth bank --quiet
for m in frenbrdf nbrdf hyperbrdf; do
  t=$(date +%s)
  frenbrdf train --method $m --training demo --data merl --out runs/$m --seeds $seeds --quiet --json
  echo "train $m (seeds $seeds) $(( $(date +%s) - t )) s"
done
t=$(date +%s)
frenbrdf evaluate runs/*/seed-* --out eval-merl --quick --refine latent --quiet
frenbrdf evaluate runs/*/seed-* --out eval-merl-on-bank --data bank --all --max-materials 40 --quick --refine latent --quiet
echo "evaluate $(( $(date +%s) - t )) s"
echo "total $(( $(date +%s) - start )) s"
