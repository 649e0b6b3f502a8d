#!/usr/bin/env bash
# The from-scratch folds against their control: held-out measurements (three draws) and the 46 tables.
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1
M="local/folds/scratch-control local/folds/scratch-fold1 local/folds/scratch-fold2 local/v2-packed"
T="fold/1=acrylic_felt_green_rgb fold/1=vch_golden_yellow_rgb fold/2=paper_white_rgb fold/2=cg_sunflower_rgb"
D=research/results/measured-training/scratch
python research/studies/compare_models.py --models $M --labels control fold/1 fold/2 v2 --measurements ../shared/data/rgl-measured/*.bsdf \
  --draws 0 1 2 --budgets none latent full --trained-on $T --out $D/held-out > /tmp/s-a.log 2>&1 &
python research/studies/compare_models.py --models $M --labels control fold/1 fold/2 v2 \
    --held-out research/results/encoder-refit/config-plain.json local/v2/data --draws 0 --out $D/tables > /tmp/s-b.log 2>&1 &
wait
