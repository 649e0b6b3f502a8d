#!/usr/bin/env bash
# Regenerates the shipped model (docs/pretrained.md), version 10's recipe (research/results/version-9 and
# second-look): the training folders from ../shared/data, the decoder's training run (on a GPU where torch sees one:
# shipped_model.json says device "auto"), its four device encoders, the decoder with its own encoder and the four,
# `best-fit` (version 9), then a second look for them, packed into the package with its card.
#
#   bash release/train_shipped_model.sh [SHARED_DATA] [WORK] [ARGS]  # then: git diff python/frenbrdf/models/pretrained
#
# ARGS go to train_shipped_model.py (e.g. --trained-on "one NVIDIA H200"). A rerun after a failure goes on where it
# stopped: each finished stage leaves a mark in WORK/done and is not run again, and a training stopped midway
# continues from its last.pt.
#
# Data: the published NBRDF fits of the MERL materials, the RGL fits of every material that has no real measurement
# in SHARED_DATA/rgl-measured, the measurements themselves (.bsdf), the default bank and 45 procedural families.
# shipped_model.json holds out version 8's test tables (its `holdout`) for the card.
set -euo pipefail
SHARED=${1:-../shared/data}
WORK=${2:-pretrained-work}
HERE=$(dirname "$0")
source "$HERE/link_inputs.sh"
mkdir -p "$WORK/measured" "$WORK/done"

stage() {  # stage NAME COMMAND...: runs COMMAND unless stage NAME finished in an earlier run
    [[ -f "$WORK/done/$1" ]] && return 0
    "${@:2}"
    touch "$WORK/done/$1"
}
resume_if_started() {  # --resume where the run folder $1 holds a last.pt
    [[ -f "$1/last.pt" ]] && echo --resume || true
}

stage merl frenbrdf import-nbrdf "$SHARED"/merl-nbrdf/*.h5 "$WORK/merl" --quiet
fits=()
for fit in "$SHARED"/rgl-nbrdf/*.h5; do
    [[ -f "$SHARED/rgl-measured/$(basename "$fit" .h5).bsdf" ]] || fits+=("$fit")
done
stage rgl-fits frenbrdf import-nbrdf "${fits[@]}" "$WORK/rgl-fits" --quiet
link_into "$WORK/measured" "$SHARED"/rgl-measured/*.bsdf
stage bank frenbrdf synth "$WORK/bank" --quiet
stage families frenbrdf synth "$WORK/families" --n 45 --seed 0 --mix families --quiet

# The decoder, packed alone (WORK/base), trained on a folder of links to the five (WORK/base-work/data).
stage decoder python "$HERE/train_shipped_model.py" --merl "$WORK/merl" --bank "$WORK/bank" --data "$WORK/rgl-fits" \
    --data "$WORK/measured" --data "$WORK/families" --config "$HERE/shipped_model.json" --work "$WORK/base-work" \
    --dest "$WORK/base" --card "$WORK/base.md" --quiet $(resume_if_started "$WORK/base-work/run") "${@:3}"
# Its four device encoders (research/results/folds-v8's amendment), two at a time.
stage encoder-configs python "$HERE/../research/results/folds-v8/pipeline/encoder_configs.py" \
    "$WORK/base-work/run/config.json" "$WORK/base" "$WORK/encoder-configs"
KINDS="mixed-mean mixed-attention devices-mean devices-attention"
for kind in $KINDS; do echo "$kind"; done | xargs -P 2 -L 1 bash -c '
    [[ -f "$0/done/encoder-$1" ]] && exit 0
    resume=(); [[ -f "$0/encoders/$1/last.pt" ]] && resume=(--resume)
    frenbrdf train --data "$0/base-work/data" --config "$0/encoder-configs/$1.json" --seed 0 --out "$0/encoders/$1" \
        --quiet "${resume[@]}" && touch "$0/done/encoder-$1"' "$WORK"
members=()
for kind in $KINDS; do members+=("$WORK/encoders/$kind"); done
stage v9 python "$HERE/pack_encoder_mean.py" --base "$WORK/base" --members "${members[@]}" --choice best-fit \
    --why '[version-9](../research/results/version-9/README.md)' --version 9 --work "$WORK/base-work" \
    --dest "$WORK/v9" --card "$WORK/v9.md"
# The second look for version 9's encoders (research/results/second-look): three runs on the tables of the decoder's
# data (the merl, bank and rgl-fits folders: the same split as the judged runs), all at once; all three are packed
# with version 9 into the package, their answers averaged (research/results/look-ensemble), taking two looks
# (research/results/repeated-look), with its card.
mkdir -p "$WORK/look-data"
(shopt -s nullglob; link_into "$WORK/look-data" "$WORK"/merl/*.binary "$WORK"/bank/*.binary "$WORK"/rgl-fits/*.binary)
for seed in 1 2 3; do echo "$seed"; done | xargs -P 3 -L 1 bash -c '  # $0 WORK, $1 this folder, $2 the seed
    [[ -f "$0/done/look-$2" ]] && exit 0
    python "$1/../research/studies/second_look.py" train "$1/shipped_model.json" "$0/look-data" --base "$0/v9" \
        --out "$0/looks/s$2" --epochs 300 --minutes 600 --seed "$2" --quiet && touch "$0/done/look-$2"' "$WORK" "$HERE"
python "$HERE/pack_second_look.py" --base "$WORK/v9" --looks "$WORK"/looks/s{1,2,3} --work "$WORK/base-work" \
    --mean --steps 2 --version 12 \
    --why '[second-look](../research/results/second-look/README.md), two looks by [repeated-look](../research/results/repeated-look/README.md), three averaged by [look-ensemble](../research/results/look-ensemble/README.md)'
