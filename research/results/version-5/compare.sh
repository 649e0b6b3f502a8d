#!/usr/bin/env bash
# Version 5 against version 4 (research/results/version-5): the same 42 held-out test materials of their common
# split (neither trained on them) and the 19 real measurements (each version left out of what its split trained
# on: the fits of 13 of them): through the six device patterns at 1,500 samples, encoder only (OUT/patterns), and
# from 4,000 random bins with the encoder, `latent` and `full` (OUT/refined). Two processes. V4 is version 4's packed folder (a copy of
# python/frenbrdf/models/pretrained from before version 5), RUN version 5's training run (its split.json, data/).
#
#   bash research/results/version-5/compare.sh V4 RUN OUT
set -euo pipefail
V4=${1:?version 4 folder}; RUN=${2:?version 5 training work folder}; OUT=${3:?OUT folder}
tables=$(python -c "import json,sys; print(' '.join(f'{sys.argv[2]}/data/{n}.binary' for n in json.load(open(sys.argv[1]))['test']))" "$RUN/run/split.json" "$RUN")
trained_on=$(python -c "
import json, sys, pathlib
split = json.load(open(sys.argv[1])); seen = set(split['train']) | set(split['val'])
names = [p.stem for p in pathlib.Path('../shared/data/rgl-measured').glob('*.bsdf') if p.stem in seen]
print(' '.join(f'{label}={n}' for label in ('v4', 'v5') for n in names))" "$RUN/run/split.json")
COMPARE=(python research/studies/compare_models.py --models "$V4" pretrained --labels v4 v5 --tables $tables
         --measurements ../shared/data/rgl-measured/*.bsdf --trained-on $trained_on --resolution 128)
OMP_NUM_THREADS=1 "${COMPARE[@]}" --patterns merl-bins uniform in-plane gonioreflectometer image-based specular \
    --samples 1500 --budgets none --out "$OUT/patterns" > "$OUT-patterns.log" 2>&1 &
OMP_NUM_THREADS=1 "${COMPARE[@]}" --samples 4000 --budgets none latent full --out "$OUT/refined" > "$OUT-refined.log" 2>&1 &
wait
