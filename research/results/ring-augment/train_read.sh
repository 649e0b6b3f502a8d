#!/usr/bin/env bash
# ring-augment's exploration (README.md): one short training of version 8's recipe (folds-v8/config-v8.json) on
# a small folder of materials, with the holdout, split, epochs and augmentation given, no early stop, then its last
# checkpoint read on the measurements given (4,000 random valid bins, draw 0; encoder, `latent`, `full`).
#
#   bash research/results/ring-augment/train_read.sh NAME DATA SEED EPOCHS HOLDOUT AUGMENT MEASUREMENT...
#   e.g. ... one-noaug local/irid/one 0 1500 paper_white_rgb "mix=0 gain=0 hue_turn=0" irid_flake_paint2_rgb
set -euo pipefail
NAME=$1; DATA=$2; SEED=$3; EPOCHS=$4; HOLDOUT=$5; AUGMENT=$6; shift 6
HERE=$(dirname "$0"); WORK=local/irid
mkdir -p "$WORK"
python - "$HERE/../folds-v8/config-v8.json" "$WORK/$NAME.json" "$EPOCHS" "$HOLDOUT" "$AUGMENT" <<'PY'
import json, sys
source, target, epochs, holdout, augment = sys.argv[1:]
config = json.load(open(source))
config.update(holdout=holdout.split(","), split=[0.9, 0.1, 0.0], epochs=int(epochs), patience=0, lr_plateau=0,
              render_every=0)
for change in augment.split():
    key, value = change.split("=")
    config["augment"][key] = float(value)
json.dump(config, open(target, "w"), indent=1)
PY
OMP_NUM_THREADS=${THREADS:-2} frenbrdf train --data "$DATA" --config "$WORK/$NAME.json" --seed "$SEED" \
    --out "$WORK/$NAME" --quiet > "$WORK/$NAME.log" 2>&1
OMP_NUM_THREADS=${THREADS:-2} python "$HERE/../../studies/compare_models.py" --resolution 128 --out "$WORK/$NAME-read" \
    --models "$WORK/$NAME/last.pt" --labels "$NAME" --samples 4000 --budgets none latent full \
    --measurements $(for m in "$@"; do echo "../shared/data/rgl-measured/$m.bsdf"; done) > "$WORK/$NAME-read.log" 2>&1
