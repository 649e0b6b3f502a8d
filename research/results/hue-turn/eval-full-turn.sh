#!/usr/bin/env bash
# hue_turn 1.0 against 0.5, three seeds each (README.md beside this file, "Every gained table turned"), one
# thread each, the two at once: the 46 held-out tables (draw 0) and the four measurements (draws 0-2).
set -eu
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
D=research/results/hue-turn/full-turn
M="local/hue-turn/s0 local/hue-turn/s1 local/hue-turn/s3 local/hue-turn/full-s0 local/hue-turn/full-s1 local/hue-turn/full-s3"
L="half/0 half/1 half/3 full/0 full/1 full/3"
python research/studies/compare_models.py --models $M --labels $L \
    --held-out research/results/hue-turn/config.json local/v2/data --draws 0 --budgets none latent \
    --out $D/tables > local/hue-turn/full-tables.log 2>&1 &
python research/studies/compare_models.py --models $M --labels $L --measurements ../shared/data/rgl-measured/*.bsdf \
    --draws 0 1 2 --budgets none latent full --out $D/measured > local/hue-turn/full-measured.log 2>&1 &
wait
