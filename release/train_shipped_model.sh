#!/usr/bin/env bash
# Regenerates the shipped model (docs/pretrained.md), version 9's recipe (research/results/version-9): the training
# folders from ../shared/data, the decoder's training run (on a GPU where torch sees one: shipped_model.json says
# device "auto"), its four device encoders, then the decoder with its own encoder and the four, `best-fit`, packed
# into the package with its card.
#
#   bash release/train_shipped_model.sh [SHARED_DATA] [WORK]        # then: git diff python/frenbrdf/models/pretrained
#
# Data: the published NBRDF fits of the MERL materials, the RGL fits of every material that has no real measurement
# in SHARED_DATA/rgl-measured, the measurements themselves (.bsdf), the default bank and 45 procedural families.
# shipped_model.json holds out version 8's test tables (its `holdout`) for the card.
set -euo pipefail
SHARED=${1:-../shared/data}
WORK=${2:-pretrained-work}
HERE=$(dirname "$0")
source "$HERE/link_inputs.sh"
mkdir -p "$WORK/measured"

frenbrdf import-nbrdf "$SHARED"/merl-nbrdf/*.h5 "$WORK/merl" --quiet
fits=()
for fit in "$SHARED"/rgl-nbrdf/*.h5; do
    [[ -f "$SHARED/rgl-measured/$(basename "$fit" .h5).bsdf" ]] || fits+=("$fit")
done
frenbrdf import-nbrdf "${fits[@]}" "$WORK/rgl-fits" --quiet
link_into "$WORK/measured" "$SHARED"/rgl-measured/*.bsdf
frenbrdf synth "$WORK/bank" --quiet
frenbrdf synth "$WORK/families" --n 45 --seed 0 --mix families --quiet

# The decoder, packed alone (WORK/base), trained on a folder of links to the five (WORK/base-work/data).
python "$HERE/train_shipped_model.py" --merl "$WORK/merl" --bank "$WORK/bank" --data "$WORK/rgl-fits" \
    --data "$WORK/measured" --data "$WORK/families" --config "$HERE/shipped_model.json" --work "$WORK/base-work" \
    --dest "$WORK/base" --card "$WORK/base.md" --quiet
# Its four device encoders (research/results/folds-v8's amendment), two at a time.
python "$HERE/../research/results/folds-v8/pipeline/encoder_configs.py" "$WORK/base-work/run/config.json" \
    "$WORK/base" "$WORK/encoder-configs"
KINDS="mixed-mean mixed-attention devices-mean devices-attention"
for kind in $KINDS; do echo "$kind"; done | xargs -P 2 -L 1 bash -c \
    'frenbrdf train --data "$0/base-work/data" --config "$0/encoder-configs/$1.json" --seed 0 --out "$0/encoders/$1" --quiet' \
    "$WORK"
members=()
for kind in $KINDS; do members+=("$WORK/encoders/$kind"); done
python "$HERE/pack_encoder_mean.py" --base "$WORK/base" --members "${members[@]}" --choice best-fit \
    --why '[version-9](../research/results/version-9/README.md)' --version 9 --work "$WORK/base-work"
