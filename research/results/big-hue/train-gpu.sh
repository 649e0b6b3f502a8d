#!/usr/bin/env bash
# The big-hue study's runs (README.md beside this file): the larger model with the hue turn, seeds 0, 1
# and 3, three at once on a lent GPU, by research/studies/train-gpu.sh:
#
#   run: LIMIT=525 bash research/results/big-hue/train-gpu.sh   (carry: .devdata, python/frenbrdf/_native.abi3.so)
#
# then each run its limit stopped is finished on the CPU: `frenbrdf train --data local/v2/data --config
# research/results/big-hue/config.json --seed S --device cpu --resume --out local/big-hue/sS` (last.pt put back).
C=research/results/big-hue/config.json
WORK=${WORK:-/tmp/big-hue} THREADS=${THREADS:-5} exec bash research/studies/train-gpu.sh s0=0:$C s1=1:$C s3=3:$C
