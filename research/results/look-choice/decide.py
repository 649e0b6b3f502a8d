"""The rule of research/results/look-choice (README.md), from run.sh's readings.

    python research/results/look-choice/decide.py OUT

Per material, eight looks with the best-fit choice − version 11 (two looks, the last), in render PSNR (means over
both draws); the rule of research/studies/look_rule.py with the new families first and the tables second.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from look_rule import decide  # noqa: E402

if __name__ == "__main__":
    raise SystemExit(decide(Path(sys.argv[1]), "best8", "v11", "8 looks, best-fit − version 11",
                            "PASSES, the model takes eight looks and keeps the best-fitting z"))
