#!/usr/bin/env bash
# Training runs of a study on a lent GPU machine (the device tool), several at once, each for at most
# LIMIT seconds, with a copy of ../shared/data carried as .devdata:
#
#   run: LIMIT=520 bash research/studies/train-gpu.sh NAME=SEED:CONFIG ...
#        (carry: .devdata, python/frenbrdf/_native.abi3.so as `pip install` builds it: a `cargo build` one
#        links this machine's libpython and fails to import there)
#   run: RESUME=1 LIMIT=225 bash research/studies/train-gpu.sh NAME=SEED:CONFIG ...   (same warm machine)
#
# Rebuilds version 2's tables as release/train_shipped_model.sh does (the MERL fits, the RGL fits but the four
# measured materials, the default bank; `md5sum` of three printed to check them against the CPU's), then
# trains the runs. HELD_OUT (names, space-separated) replaces the four RGL fits left out. RESUME=1 continues
# each run from its last.pt on the tables already there; on a CPU, `frenbrdf train --resume` from the last.pt
# that comes back does the same.
# Writes OUT/run-NAME.tgz (the run folder with best.pt stripped of its optimizer state, its log) and, for
# the runs named in KEEP_LAST (default: all), OUT/last-NAME.pt for a resume (at most 64 MiB come back).
set -uo pipefail
export PYTHONPATH=$PWD/python PYTHONUNBUFFERED=1
SHARED=${SHARED:-.devdata}
WORK=${WORK:-/tmp/gpu-runs}
source "$(dirname "$0")/../../release/link_inputs.sh"
OUT=${OUT:-$WORK/out}
LIMIT=${LIMIT:-470}
DEVICE=${DEVICE:-cuda}
THREADS=${THREADS:-4}
EPOCHS=${EPOCHS:-}          # a test of this script: a few epochs, and BANK_N=4 bank materials
RUNS=("$@")
names=("${RUNS[@]%%=*}")
KEEP_LAST=${KEEP_LAST:-${names[*]}}
frenbrdf() { python3 -m frenbrdf.cli "$@"; }
mkdir -p "$WORK" "$OUT"
nvidia-smi -L 2>/dev/null
python3 -c "import torch; print('torch', torch.__version__, 'cuda', torch.cuda.is_available())"

if [[ -z ${RESUME:-} ]]; then
    HELD_OUT=" ${HELD_OUT:-paper_white_rgb acrylic_felt_green_rgb vch_golden_yellow_rgb cg_sunflower_rgb} "
    rgl=()
    for fit in "$SHARED"/rgl-nbrdf/*.h5; do
        [[ "$HELD_OUT" == *" $(basename "$fit" .h5) "* ]] || rgl+=("$fit")
    done
    merl=("$SHARED"/merl-nbrdf/*.h5)
    half=$(( ${#merl[@]} / 2 ))
    start=$SECONDS
    frenbrdf import-nbrdf "${merl[@]:0:half}" "$WORK/merl-a" --quiet &
    frenbrdf import-nbrdf "${merl[@]:half}" "$WORK/merl-b" --quiet &
    frenbrdf import-nbrdf "${rgl[@]}" "$WORK/rgl" --quiet &
    frenbrdf synth "$WORK/bank" ${BANK_N:+--n $BANK_N} --quiet &
    wait
    mkdir -p "$WORK/data"
    # A failed earlier try on the same warm machine can leave links into its own folders dangling (one failed the
    # next): those go, and nothing else in the folder.
    find "$WORK/data" -maxdepth 1 -xtype l -lname "$(realpath "$WORK")/*" -delete
    link_into "$WORK/data" "$WORK"/{merl-a,merl-b,rgl,bank}/*.binary || exit 1
    echo "tables: $(ls "$WORK/data" | wc -l) in $((SECONDS - start)) s"
    md5sum "$WORK"/data/{alumina-oxide,cm_white_rgb,synth-000-orange-fabric}.binary
fi

train() {  # name seed config
    OMP_NUM_THREADS=$THREADS MKL_NUM_THREADS=$THREADS timeout "$LIMIT" python3 -m frenbrdf.cli train \
        --data "$WORK/data" --config "$3" --seed "$2" --device "$DEVICE" ${EPOCHS:+--epochs $EPOCHS} \
        ${RESUME:+--resume} --out "$WORK/$1" --quiet --json > "$WORK/$1${RESUME:+.resume}.log" 2>&1
    echo "$1: exit $? after $((SECONDS - start)) s; $(python3 -c "import json, sys; h = json.load(open(sys.argv[1]))[1:]; \
print(len(h), 'epochs, last lr', h[-1]['lr'], 'best val_rec', min(e['val_rec'] for e in h))" "$WORK/$1/history.json" 2>&1 | tail -1)"
}
start=$SECONDS
for run in "${RUNS[@]}"; do
    spec=${run#*=}
    train "${run%%=*}" "${spec%%:*}" "${spec#*:}" &
done
wait
# Evaluation needs best.pt's weights alone; best-psnr.pt stays behind.
python3 - "${names[@]/#/$WORK/}" <<'PY'
import sys, torch
for run in sys.argv[1:]:
    checkpoint = torch.load(f"{run}/best.pt", map_location="cpu", weights_only=True)
    checkpoint["optimizer"]["state"] = {}
    torch.save(checkpoint, f"{run}/best.pt")
PY
for name in "${names[@]}"; do
    tar czf "$OUT/run-$name.tgz" -C "$WORK" --exclude last.pt --exclude best-psnr.pt "$name" $(cd "$WORK" && ls "$name".*log)
    [[ " $KEEP_LAST " == *" $name "* ]] && cp "$WORK/$name/last.pt" "$OUT/last-$name.pt"
done
ls -la "$OUT"
