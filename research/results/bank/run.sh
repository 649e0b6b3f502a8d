#!/bin/bash
# The default bank (100 analytic materials): every method at the demo's length over three seeds
# (each its own split and initialisation), then the evaluation on the bank's test splits and on
# the MERL-derived materials none of them saw (out of distribution). The augmentation's own
# evidence (against the tables alone) is research/colour.md's, made with research/studies/colour_ablation.py.
# Usage: research/results/bank/run.sh [FOLDER]   (default bank-protocol; ../shared beside the repository)
set -e
shared=$(cd "$(dirname "$0")/../../../../shared" && pwd)
mkdir -p "${1:-bank-protocol}" && cd "${1:-bank-protocol}"
export OMP_NUM_THREADS=1   # one thread a job: two jobs side by side use the 2 cores best
start=$(date +%s)
[ -f bank/bank.json ] || frenbrdf synth bank --quiet
[ -d merl ] || frenbrdf import-nbrdf "$shared"/data/merl-nbrdf/*.h5 merl --quiet
for m in frenbrdf nbrdf hyperbrdf; do
  t=$(date +%s)
  frenbrdf train --method $m --training demo --data bank --out runs/$m --seeds 0 1 2 --quiet --json
  echo "train $m (seeds 0 1 2) $(( $(date +%s) - t )) s"
done
t=$(date +%s)
frenbrdf evaluate runs/*/seed-* --out eval-bank --quick --refine latent --quiet
frenbrdf evaluate runs/*/seed-* --out eval-bank-on-merl --data merl --all --max-materials 40 --quick --refine latent --quiet
echo "evaluate $(( $(date +%s) - t )) s"
echo "total $(( $(date +%s) - start )) s"
