#!/usr/bin/env bash
# The real-encoders study's two runs (README.md): encoders for version 6's frozen decoder, with the `mixed`
# encoders' own config, on version 4's data plus the .bsdf measurements of the 13 materials version 4 trained on
# (as fits) and the procedural families. Two at a time, one thread each.
#
#   bash research/results/real-encoders/train.sh V4DATA FAMILIES BASE WORK
#   (V4DATA: version 4's tables, e.g. local/v5/release/work/data; FAMILIES: e.g. local/v5/families;
#    BASE: the `mixed` run whose config is reused, e.g. local/v5/frozen/mixed-s0)
set -euo pipefail
V4DATA=${1:?}; FAMILIES=${2:?}; BASE=${3:?}; WORK=${4:?}
MEASURED=${MEASURED:-../shared/data/rgl-measured}
source "$(dirname "$0")/../../../release/link_inputs.sh"
mkdir -p "$WORK/data"
link_into "$WORK/data" "$V4DATA"/* "$FAMILIES"/*.binary
while read -r name; do
    # Beside the material's fit, under a name of its own (a folder holds one file per material).
    if [[ -f "$MEASURED/$name.bsdf" ]]; then link_as "$WORK/data/$name-measured.bsdf" "$MEASURED/$name.bsdf"; fi
done < research/studies/sampling_patterns/v4-trained-on.txt
echo "$(ls "$WORK"/data/*.bsdf | wc -l) measurements, $(ls "$WORK"/data/*.binary | wc -l) tables in $WORK/data"
# The base run's config, its data and output fields aside (the command line gives them).
python - "$BASE/config.json" "$WORK/config.json" <<'PY'
import json, sys
config = json.load(open(sys.argv[1]))
for field in ("data", "out", "seed"):
    config.pop(field, None)
json.dump(config, open(sys.argv[2], "w"), indent=1)
PY
for seed in 0 1; do echo "$seed"; done | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c \
    'frenbrdf train --data "$0/data" --config "$0/config.json" --seed "$1" --out "$0/real-s$1" --quiet \
        > "$0/real-s$1.log" 2>&1' "$WORK"
