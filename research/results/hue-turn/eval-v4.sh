#!/usr/bin/env bash
# Version 3 (shipped) against the version-4 candidate (README.md beside this file: the shipping rule), one
# thread each, the two at once: the four measurements (draws 0-2) and the 42 materials of version 2's
# held-out test split (local/v2/split.json), which neither model trained on.
set -eu
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
V3=${V3:-pretrained}
V4=${V4:-local/v4/packed}
T=$(python -c "import json; print(' '.join('local/v2/data/' + n + '.binary' for n in json.load(open('local/v2/split.json'))['test']))")
D=research/results/hue-turn
python research/studies/compare_models.py --models $V3 $V4 --labels v3 v4 --measurements ../shared/data/rgl-measured/*.bsdf \
    --draws 0 1 2 --budgets none latent full --out $D/v4-measured > local/v4/measured.log 2>&1 &
python research/studies/compare_models.py --models $V3 $V4 --labels v3 v4 --tables $T --draws 0 --out $D/v4-test-split \
    > local/v4/tables.log 2>&1 &
wait
