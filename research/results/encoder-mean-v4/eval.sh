#!/usr/bin/env bash
# The mean of seven against version 4 (README.md beside this file: the rule). Packs the candidate into
# local/mean-v4/packed (release/pack_encoder_mean.py: version 4's decoder, its encoder and the six of train.sh),
# then, one thread each, the two at once: the 46 held-out tables (draw 0, encoder only and `latent`) and
# the four measurements (draws 0-2; encoder, `latent`, `full`).
set -eu
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
D=research/results/encoder-mean-v4
python release/pack_encoder_mean.py --members local/mean-v4/plain-s{1,2,3,4,5,6} --work local/v2 --version 5 \
    --dest local/mean-v4/packed --card local/mean-v4/card.md > local/mean-v4/pack.log 2>&1
python research/studies/compare_models.py --models pretrained local/mean-v4/packed --labels v4 mean7 \
    --held-out $D/config.json local/v2/data \
    --draws 0 --budgets none latent --out $D/tables > local/mean-v4/tables.log 2>&1 &
python research/studies/compare_models.py --models pretrained local/mean-v4/packed --labels v4 mean7 \
    --measurements ../shared/data/rgl-measured/*.bsdf --draws 0 1 2 --budgets none latent full --out $D/measured \
    > local/mean-v4/measured.log 2>&1 &
wait
