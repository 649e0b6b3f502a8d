#!/usr/bin/env bash
# The pipeline amendment's training on a lent GPU (../README.md): version 8's four kinds of device encoder for each
# fold decoder (v8-s0 … v8-s2, packed in .devpack by encoder_configs.py's steps), twelve runs at once with one CPU
# thread each, each for at most LIMIT seconds; then each fold's candidate (its own encoder and its four, `best-fit`)
# packed. Brings back the candidates, each run's history and log, nothing else (the runs' checkpoints hold the
# frozen decoder: twelve of them would not fit in what comes back).
#
#   run (carry .devdata .devpack python/frenbrdf/_native.abi3.so):
#       LIMIT=450 bash research/results/folds-v8/pipeline/train-gpu.sh
set -uo pipefail
export PYTHONPATH=$PWD/python
WORK=${WORK:-/tmp/gpu-runs}
KINDS="mixed-mean mixed-attention devices-mean devices-attention"
runs=()
for seed in 0 1 2; do for kind in $KINDS; do runs+=("s$seed-$kind=$seed:.devpack/cfg-s$seed/$kind.json"); done; done
HELD_OUT="$(python3 research/studies/measured_folds/folds.py all)" THREADS=1 KEEP_LAST=- OUT=$WORK/out \
    bash research/studies/train-gpu.sh "${runs[@]}"
for seed in 0 1 2; do
    members=()
    for kind in $KINDS; do [[ -f $WORK/s$seed-$kind/best.pt ]] && members+=("$WORK/s$seed-$kind"); done
    python3 research/results/device-specialists/pack.py "$OUT/cand-s$seed" "${members[@]}" --base ".devpack/v8-s$seed"
    for kind in $KINDS; do
        mkdir -p "$OUT/runs/s$seed-$kind"
        cp "$WORK/s$seed-$kind"/{config.json,history.json} "$WORK/s$seed-$kind.log" "$OUT/runs/s$seed-$kind/" 2>/dev/null
    done
done
ls -la "$OUT" "$OUT"/cand-s*
