#!/usr/bin/env bash
# The sampling-patterns study's scores (research/results/sampling-patterns): every run of train.sh and the
# shipped version 4 read the 39 held-out tables and the 19 real measurements through six patterns at 300, 1,500
# and 4,000 samples (encoder only), and the seed-0 runs and version 4 at 1,500 refined (`latent`: a second a
# material, so one seed). Version 4 is not scored on what it trained on (its split's train and validation
# materials, the fits of 13 of the measurements among them: v4-trained-on.txt). One scoring per finished run of
# WORK (its log's last line names its folder) and v4, two at a time (a scoring already in OUT is kept), then one
# summary over all rows.
#
#   bash research/studies/sampling_patterns/evaluate.sh DATA WORK OUT
set -euo pipefail
DATA=${1:?DATA folder}; WORK=${2:?WORK folder of train.sh}; OUT=${3:?OUT folder}
HERE=$(dirname "$0")
export HERE DATA OUT
trained_on=""; while read -r name; do [[ -n "$name" ]] && trained_on+=" v4=$name"; done < "$HERE/v4-trained-on.txt"
export trained_on
score() {  # MODEL LABEL NAME
    [[ -f "$OUT/$3/compare.json" ]] && return 0
    local extra=(--budgets none)
    [[ "$2" == v4 || "$2" == */s0 ]] && extra=(--budgets none latent)
    [[ "$2" == v4 ]] && extra+=(--trained-on $trained_on)
    python "$HERE/../compare_models.py" --models "$1" --labels "$2" --measurements ../shared/data/rgl-measured/*.bsdf \
        --held-out "$HERE/paper-mean.json" "$DATA" \
        --patterns merl-bins uniform in-plane gonioreflectometer image-based specular --samples 300 1500 4000 \
        --refine-counts 1500 --resolution 128 "${extra[@]}" --out "$OUT/$3" > "$OUT/$3.log" 2>&1
}
export -f score
mkdir -p "$OUT"
{ echo "pretrained v4 v4"
  for log in "$WORK"/*-s[0-9].log; do
      grep -qs "run folder" "$log" || continue
      run=$(basename "$log" .log); echo "$WORK/$run ${run%-s*}/s${run##*-s} $run"
  done; } | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c 'score "$0" "$1" "$2"'
python "$HERE/merge.py" "$OUT"/*/compare.json --out "$OUT"
