#!/usr/bin/env bash
# The capacity study's GPU runs (README.md beside this file): the larger model, seeds 0, 1 and 3, and
# version 2's model, seed 0 (a check of GPU against CPU), four at once, by research/studies/train-gpu.sh:
#
#   run: LIMIT=465 bash research/results/capacity/train-gpu.sh   (carry: .devdata, python/frenbrdf/_native.abi3.so)
#   run: RESUME=1 LIMIT=225 bash research/results/capacity/train-gpu.sh   (at once, on the same warm machine)
BIG=research/results/capacity/config-big.json
SMALL=research/results/measured-training/config-scratch.json
WORK=${WORK:-/tmp/capacity} KEEP_LAST=${KEEP_LAST:-"big-s0 big-s1 big-s3"} exec bash research/studies/train-gpu.sh \
    big-s0=0:$BIG big-s1=1:$BIG big-s3=3:$BIG control-gpu-s0=0:$SMALL
