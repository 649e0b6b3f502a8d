#!/usr/bin/env bash
# Regenerates the shipped model (docs/pretrained.md): the training folders from ../shared/data (the
# MERL fits, the RGL fits, the default bank and the `features` bank of car paints, retro-reflection,
# thin films, sheen and coats), one training run (on a GPU where torch sees one: benches/pretrained.json
# says device "auto"), packing and the model card. The four RGL materials whose real measurements
# docs/measurements.md reports are never trained on: their fits are left out here.
#
#   bash benches/pretrained.sh [SHARED_DATA] [WORK]        # then: git diff python/frenbrdf/models/pretrained
#
# The shipped version 3 was trained by this script's data and config on the 2-core AMD EPYC CPU of
# a development machine (`frenbrdf train --data WORK/pack/data --config benches/pretrained.json
# --out WORK/pack/run`, 580 epochs, stopped by patience after the plateau schedule had taken the
# learning rate to 4e-6; 1187 s of training, 21.5 min wall), then packed here with --reuse
# --trained-on "AMD EPYC, 2 cores (CPU)".
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
frenbrdf synth "$WORK/features" --mix features --n 60 --seed 1 --quiet
python benches/pretrained.py --merl "$WORK/merl" --bank "$WORK/bank" --data "$WORK/rgl-train" --data "$WORK/features" \
    --config benches/pretrained.json --work "$WORK/pack" "${@:3}"
