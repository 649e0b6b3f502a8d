#!/usr/bin/env bash
# The capacity study's evaluation (README.md beside this file): the six runs, and control seed 0 trained
# on the GPU, on the 46 held-out tables (draw 0) and the four measurements (draws 0-2), one thread each,
# the two at once. Writes research/results/capacity/{tables,measured}.
set -eu
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
M="local/folds/scratch-control local/folds/seed1-control local/folds/seed3-control
   local/capacity/big-s0 local/capacity/big-s1 local/capacity/big-s3 local/capacity/control-gpu-s0"
L="control/0 control/1 control/3 big/0 big/1 big/3 control-gpu/0"
D=research/results/capacity
python research/studies/compare_models.py --models $M --labels $L \
    --held-out research/results/measured-training/config-scratch.json local/v2/data --draws 0 --out $D/tables > local/capacity/tables.log 2>&1 &
python research/studies/compare_models.py --models $M --labels $L --measurements ../shared/data/rgl-measured/*.bsdf \
    --draws 0 1 2 --budgets none latent full --out $D/measured > local/capacity/measured.log 2>&1 &
wait
