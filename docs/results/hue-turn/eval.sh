#!/usr/bin/env bash
# The hue-turn study's evaluation (README.md beside this file), one thread each, the two at once.
set -eu
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
H=$(python -c "import json; print(' '.join('local/v2/data/' + n + '.binary' for n in
    json.load(open('docs/results/measured-training/config-scratch.json'))['holdout']))")
M="local/folds/scratch-control local/folds/seed1-control local/folds/seed3-control local/hue-turn/s0 local/hue-turn/s1"
L="control/0 control/1 control/3 hue-turn/0 hue-turn/1"
D=docs/results/hue-turn
python benches/studies/compare_models.py --models $M --labels $L --tables $H --draws 0 --out $D/tables \
    > local/hue-turn/tables.log 2>&1 &
python benches/studies/compare_models.py --models $M --labels $L --measurements ../shared/data/rgl-measured/*.bsdf \
    --draws 0 1 2 --budgets none latent full --out $D/measured > local/hue-turn/measured.log 2>&1 &
wait
