#!/usr/bin/env bash
# The bright-carpaint study's evaluation (README.md beside this file): three seeds of hue, features-hue and
# bright-carpaint on the 46 held-out tables (draw 0; the 7 RGL fits among them summarised apart) and the four
# measurements (draws 0-2), one thread each, the two at once.
set -eu
export PYTHONPATH=$PWD/python OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
D=research/results/bright-carpaint
M="local/hue-turn/s0 local/hue-turn/s1 local/hue-turn/s3 local/bright-carpaint/s0 local/bright-carpaint/s1
   local/bright-carpaint/s3 local/feat-hue/s0 local/feat-hue/s1 local/feat-hue/s3"
L="hue/0 hue/1 hue/3 bright-carpaint/0 bright-carpaint/1 bright-carpaint/3 features-hue/0 features-hue/1
   features-hue/3"
RGL=cm_white_rgb,colodur_connemara_4c_rgb,ilm_l3_37_metallic_rgb,paper_blue_rgb,paper_green_rgb,paper_red_rgb,vch_frozen_amethyst_rgb
python research/studies/compare_models.py --models $M --labels $L --held-out research/results/hue-turn/config.json \
    local/v2/data --group "rgl-fits=$RGL" --draws 0 --out $D/tables > local/bright-carpaint/tables.log 2>&1 &
python research/studies/compare_models.py --models $M --labels $L --measurements ../shared/data/rgl-measured/*.bsdf \
    --draws 0 1 2 --budgets none latent full --out $D/measured > local/bright-carpaint/measured.log 2>&1 &
wait
