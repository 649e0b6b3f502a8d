#!/usr/bin/env bash
# Fold 1 against the control for one seed (argument: 1 or 3): the 46 held-out tables (draw 0) and the
# measurements fold 1 held out (draws 0-2; its own two skipped by --trained-on). Writes seeds/seedS/{tables,held-out}.
set -eu
seed=$1
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1
M="local/folds/seed$seed-control local/folds/seed$seed-fold1"
D=research/results/measured-training/seeds/seed$seed
python research/studies/compare_models.py --models $M --labels control fold/1 \
    --held-out research/results/encoder-refit/config-plain.json local/v2/data --draws 0 --out $D/tables
python research/studies/compare_models.py --models $M --labels control fold/1 --measurements ../shared/data/rgl-measured/*.bsdf \
  --draws 0 1 2 --budgets none latent full --trained-on fold/1=acrylic_felt_green_rgb fold/1=vch_golden_yellow_rgb --out $D/held-out
