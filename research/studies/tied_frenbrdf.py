"""``frenbrdf`` with seam-tie's training term (:func:`seam_tie.use_tie`) added to every training step's loss, in this
process only: the fold-tie study's runs (research/results/fold-tie) train the shipped recipe through it.

    TIE_WEIGHT=0.5 python research/studies/tied_frenbrdf.py train --data DATA --seed 0 --out RUN ...

(from the repository root, as real-in-data's train.sh runs it with ``FRENBRDF``).
The tie's pairs are drawn by a generator seeded from ``--seed``; everything else is ``frenbrdf``'s own command.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from seam_tie import use_tie  # noqa: E402

from frenbrdf.cli import main  # noqa: E402

if __name__ == "__main__":
    arguments = sys.argv[1:]
    seed = int(arguments[arguments.index("--seed") + 1]) if "--seed" in arguments else 0
    if "TIE_WEIGHT" not in os.environ:
        sys.exit("tied_frenbrdf.py: set TIE_WEIGHT, the tie's weight (fold-tie used 0.5)")
    use_tie(seed, float(os.environ["TIE_WEIGHT"]))
    sys.exit(main(arguments))
