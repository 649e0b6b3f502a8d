#!/usr/bin/env bash
# The bright-carpaint study's runs (README.md beside this file) on the CPU: version 2's tables (local/v2/data,
# as release/train_shipped_model.sh builds them) and the 60 materials of bank.py, version 4's config, seeds 0 and 1
# at once (one thread each; seed 1 once seed 0 has loaded its tables), then seed 3 (two threads).
set -eu
export PYTHONPATH=$PWD/python
W=local/bright-carpaint
D=research/results/bright-carpaint
frenbrdf() { python -m frenbrdf.cli "$@"; }
[[ -d $W/bank ]] || python $D/bank.py $W/bank
mkdir -p $W/data
source release/link_inputs.sh  # run from the repository root, as the paths here are
link_into $W/data "$PWD"/local/v2/data/*.binary "$PWD"/$W/bank/*.binary
echo "tables: $(ls $W/data | wc -l)"
train() {  # seed threads
    OMP_NUM_THREADS=$2 MKL_NUM_THREADS=$2 frenbrdf train --data $W/data --config research/results/hue-turn/config.json \
        --seed $1 --device cpu --out $W/s$1 --quiet --json > $W/s$1.log 2>&1
}
train 0 1 & sleep 420; train 1 1 & wait
train 3 2
