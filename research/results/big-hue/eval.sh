#!/usr/bin/env bash
# The big-hue study's evaluation (README.md beside this file): three seeds of each arm on the 46 held-out
# tables (draw 0) and the four measurements (draws 0-2), one thread each, the two at once.
set -eu
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
D=research/results/big-hue
M="local/hue-turn/s0 local/hue-turn/s1 local/hue-turn/s3 local/big-hue/s0 local/big-hue/s1 local/big-hue/s3"
L="hue/0 hue/1 hue/3 big-hue/0 big-hue/1 big-hue/3"
python research/studies/compare_models.py --models $M --labels $L \
    --held-out $D/config.json local/v2/data --draws 0 --budgets none latent --out $D/tables > local/big-hue/tables.log 2>&1 &
python research/studies/compare_models.py --models $M --labels $L --measurements ../shared/data/rgl-measured/*.bsdf \
    --draws 0 1 2 --budgets none latent full --out $D/measured > local/big-hue/measured.log 2>&1 &
wait
