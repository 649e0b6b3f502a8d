"""The rule of research/results/look-ensemble (README.md), from run.sh's readings.

    python research/results/look-ensemble/decide.py OUT

Per material, the three looks averaged (twice) − version 11, in render PSNR (means over both draws); the rule of
research/studies/look_rule.py with the new families first and the tables second.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from look_rule import decide  # noqa: E402

if __name__ == "__main__":
    raise SystemExit(decide(Path(sys.argv[1]), "ensemble", "v11", "the three looks averaged − version 11",
                            "PASSES, the three looks averaged earn a place in the shipped model"))
