#!/usr/bin/env bash
# The hue-turn study's evaluation (README.md beside this file), one thread each, the two at once: the
# three control seeds against the turned runs of SEEDS (default "0 1", the rule's) into OUT.
#   bash research/results/hue-turn/eval.sh                                                  # tables/, measured/
#   SEEDS="0 1 3" OUT=research/results/hue-turn/three-seeds bash research/results/hue-turn/eval.sh
set -eu
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
SEEDS=${SEEDS:-0 1}
D=${OUT:-research/results/hue-turn}
M="local/folds/scratch-control local/folds/seed1-control local/folds/seed3-control"
L="control/0 control/1 control/3"
for seed in $SEEDS; do M="$M local/hue-turn/s$seed"; L="$L hue-turn/$seed"; done
python research/studies/compare_models.py --models $M --labels $L \
    --held-out research/results/measured-training/config-scratch.json local/v2/data --draws 0 --out $D/tables \
    > local/hue-turn/tables.log 2>&1 &
python research/studies/compare_models.py --models $M --labels $L --measurements ../shared/data/rgl-measured/*.bsdf \
    --draws 0 1 2 --budgets none latent full --out $D/measured > local/hue-turn/measured.log 2>&1 &
wait
