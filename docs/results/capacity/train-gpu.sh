#!/usr/bin/env bash
# The capacity study's GPU runs (README.md beside this file), on a lent GPU machine through the device
# tool, with a copy of ../shared/data carried as .devdata:
#
#   run: LIMIT=465 bash docs/results/capacity/train-gpu.sh   (carry: .devdata, python/frenbrdf/_native.abi3.so)
#   run: RESUME=1 LIMIT=225 bash docs/results/capacity/train-gpu.sh   (at once, on the same warm machine)
#
# Rebuilds version 2's tables as benches/pretrained.sh does (the MERL fits, the RGL fits but the four
# measured materials, the default bank), then trains four runs at once, each for at most LIMIT seconds:
# the larger model, seeds 0, 1 and 3, and version 2's model, seed 0 (a check of GPU against CPU).
# RESUME=1 continues each run from its last.pt on the tables already there (a run LIMIT stopped; on a CPU,
# `frenbrdf train --resume` from the last.pt that comes back does the same).
# Writes OUT/run-NAME.tgz (the run folder, its log) and OUT/last-big-sS.pt.
set -uo pipefail
export PYTHONPATH=$PWD/python PYTHONUNBUFFERED=1
SHARED=${SHARED:-.devdata}
WORK=${WORK:-/tmp/capacity}
OUT=${OUT:-$WORK/out}
LIMIT=${LIMIT:-470}
DEVICE=${DEVICE:-cuda}
EPOCHS=${EPOCHS:-}          # a test of this script: a few epochs, and BANK_N=4 bank materials
frenbrdf() { python3 -m frenbrdf.cli "$@"; }
mkdir -p "$WORK" "$OUT"
nvidia-smi -L 2>/dev/null
python3 -c "import torch; print('torch', torch.__version__, 'cuda', torch.cuda.is_available())"

if [[ -z ${RESUME:-} ]]; then
    HELD_OUT=" paper_white_rgb acrylic_felt_green_rgb vch_golden_yellow_rgb cg_sunflower_rgb "
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
    ln -sf "$WORK"/{merl-a,merl-b,rgl,bank}/*.binary "$WORK/data/"
    echo "tables: $(ls "$WORK/data" | wc -l) in $((SECONDS - start)) s"
    md5sum "$WORK"/data/{alumina-oxide,cm_white_rgb,synth-000-orange-fabric}.binary
fi

train() {  # name seed config
    OMP_NUM_THREADS=4 MKL_NUM_THREADS=4 timeout "$LIMIT" python3 -m frenbrdf.cli train --data "$WORK/data" \
        --config "$3" --seed "$2" --device "$DEVICE" ${EPOCHS:+--epochs $EPOCHS} ${RESUME:+--resume} --out "$WORK/$1" --quiet --json \
        > "$WORK/$1${RESUME:+.resume}.log" 2>&1
    echo "$1: exit $? after $((SECONDS - start)) s; $(python3 -c "import json, sys; h = json.load(open(sys.argv[1]))[1:]; \
print(len(h), 'epochs, last lr', h[-1]['lr'], 'best val_rec', min(e['val_rec'] for e in h))" "$WORK/$1/history.json" 2>&1 | tail -1)"
}
start=$SECONDS
BIG=docs/results/capacity/config-big.json
SMALL=docs/results/measured-training/config-scratch.json
train big-s0 0 $BIG & train big-s1 1 $BIG & train big-s3 3 $BIG & train control-gpu-s0 0 $SMALL &
wait
# At most 64 MiB comes back: best.pt without its optimizer state (evaluation needs the weights alone), no
# best-psnr.pt, and last.pt (a resume needs all of it) for the larger model's runs only.
python3 - "$WORK"/{big-s0,big-s1,big-s3,control-gpu-s0}/best.pt <<'PY'
import sys, torch
for path in sys.argv[1:]:
    checkpoint = torch.load(path, map_location="cpu", weights_only=True)
    checkpoint["optimizer"]["state"] = {}
    torch.save(checkpoint, path)
PY
for name in big-s0 big-s1 big-s3 control-gpu-s0; do
    tar czf "$OUT/run-$name.tgz" -C "$WORK" --exclude last.pt --exclude best-psnr.pt "$name" $(cd "$WORK" && ls "$name".*log)
    [[ $name == big-* ]] && cp "$WORK/$name/last.pt" "$OUT/last-$name.pt"
done
ls -la "$OUT"
