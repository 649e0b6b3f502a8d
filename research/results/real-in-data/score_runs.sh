#!/usr/bin/env bash
# real-in-data's reading of the measurements (evaluate.sh's first part: 4,000 random bins, draw 0, encoder,
# `latent` and `full`, each measurement only by runs that did not train on it) for some runs, one process a run,
# two at a time: the seeds added after the first reading (README.md's amendment) and research/results/diffractive's
# runs. Each run WORK/ARM-fF-sS is written to OUT/fF-sS (ARM mf) or OUT/ARM-fF-sS.
#
#   bash research/results/real-in-data/score_runs.sh OUT RUN...
set -euo pipefail
OUT=${1:?OUT folder}; shift
HERE=$(dirname "$0")
for run in "$@"; do
    grep -q "best epoch" "$run.log" || { echo "error: $run has not finished (its log has no best epoch)" >&2; exit 1; }
done
mkdir -p "$OUT"
for run in "$@"; do echo "$run"; done | OMP_NUM_THREADS=1 xargs -P 2 -L 1 bash -c '
    out=$1; run=$2; name=${run##*/}; arm=${name%%-f*}; label=$arm/${name#"$arm"-}; fold=${label#*/f}; fold=${fold%%-*}
    [[ $arm == mf ]] && folder=${name#mf-} || folder=$name
    folds="python $0/../../studies/measured_folds/folds.py"
    trained_on=(); for m in $($folds others "$fold"); do trained_on+=("$label=$m"); done
    python "$0/../../studies/compare_models.py" --models "$run" --labels "$label" --trained-on "${trained_on[@]}" \
        --measurements ../shared/data/rgl-measured/*.bsdf --budgets none latent full --samples 4000 --resolution 128 \
        --group $($folds groups) comparison-four=acrylic_felt_green_rgb,paper_white_rgb,vch_golden_yellow_rgb,cg_sunflower_rgb \
        --out "$out/$folder" > "$out/$folder.log" 2>&1' "$HERE" "$OUT"
