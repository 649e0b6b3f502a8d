#!/usr/bin/env bash
# Regenerates the shipped model (docs/pretrained.md): the training folders from ../shared/data, one
# training run (on a GPU where torch sees one: release/shipped_model.json says device "auto"), packing
# and the model card. The four RGL materials whose real measurements research/measurements.md reports
# are never trained on: their fits are left out here.
#
#   bash release/train_shipped_model.sh [SHARED_DATA] [WORK]        # then: git diff python/frenbrdf/models/pretrained
#
# Version 7's decoder was trained by this config (version 4's, research/results/hue-turn, with the larger sizes of
# research/results/capacity-v4) with version 4's 42 test tables held out, on a 2-core AMD EPYC Zen 4, one
# thread, best epoch 547 of 623, 1,620 s (capacity-v4's train.sh, seed 0), then packed with --reuse and given its
# device encoders by release/pack_encoder_mean.py (research/results/capacity-v4/README.md says how).
set -euo pipefail
SHARED=${1:-../shared/data}
WORK=${2:-pretrained-work}
HELD_OUT=" paper_white_rgb acrylic_felt_green_rgb vch_golden_yellow_rgb cg_sunflower_rgb "

frenbrdf import-nbrdf "$SHARED"/merl-nbrdf/*.h5 "$WORK/merl" --quiet
rgl=()
for fit in "$SHARED"/rgl-nbrdf/*.h5; do
    [[ "$HELD_OUT" == *" $(basename "$fit" .h5) "* ]] || rgl+=("$fit")
done
frenbrdf import-nbrdf "${rgl[@]}" "$WORK/rgl-train" --quiet
frenbrdf synth "$WORK/bank" --quiet
python release/train_shipped_model.py --merl "$WORK/merl" --bank "$WORK/bank" --data "$WORK/rgl-train" \
    --config release/shipped_model.json --work "$WORK/pack" "${@:3}"
