#!/usr/bin/env bash
# Regenerates the shipped model (docs/pretrained.md): the training folders from ../shared/data, one
# training run (on a GPU where torch sees one: release/shipped_model.json says device "auto"), packing
# and the model card. The four RGL materials whose real measurements research/measurements.md reports
# are never trained on: their fits are left out here.
#
#   bash release/train_shipped_model.sh [SHARED_DATA] [WORK]        # then: git diff python/frenbrdf/models/pretrained
#
# The shipped version 4 was trained by this config (the hue turn added: research/results/hue-turn) on the
# 2-core CPU, 475 epochs, 498 s, on these folders as built earlier (local/v2), then packed with --reuse.
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
