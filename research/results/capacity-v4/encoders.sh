#!/usr/bin/env bash
# Encoders for a larger decoder (README.md, "What follows"): version 6's two kinds of device encoder, the plain
# mean and attention pooling, each with the `mixed` sampling and the config of version 5's encoders (BASE, e.g.
# local/v5/frozen/mixed-s0), the sizes set to the decoder's, trained for DECODER kept frozen. Seed SEED (default 0)
# each, two at a time on one thread each. DECODER: a packed folder, so that the encoders can be packed beside it
# (release/pack_encoder_mean.py checks that their decoder is the base's, float16 weights and all).
#
#   [SEED=1 | SEEDS="0 1"] [POOLINGS=mean] [PATIENCE=150] [INIT_FROM=MODEL] bash research/results/capacity-v4/encoders.sh BASE DATA DECODER WORK
#   (PATIENCE: epochs without a better validation loss before a run stops; default the BASE config's. POOLINGS:
#   which kinds, default both. INIT_FROM: the encoders start from this model's encoder instead of a fresh one.)
set -euo pipefail
BASE=${1:?}; DATA=${2:?}; DECODER=${3:?}; WORK=${4:?}
SEEDS=${SEEDS:-${SEED:-0}}; POOLINGS=${POOLINGS:-mean attention}
mkdir -p "$WORK"
for pooling in $POOLINGS; do
    python research/results/capacity-v4/sized_config.py "$BASE/config.json" "$WORK/$pooling.json" --pooling "$pooling" \
        ${PATIENCE:+--patience "$PATIENCE"}
done
for seed in $SEEDS; do for pooling in $POOLINGS; do echo "$pooling $seed"; done; done |
    OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c \
    'frenbrdf train --data "$1" --config "$0/$4.json" --decoder-from "$2" ${3:+--init-from "$3"} --seed "$5" \
        --out "$0/$4-s$5" --quiet > "$0/$4-s$5.log" 2>&1' "$WORK" "$DATA" "$DECODER" "${INIT_FROM:-}"
