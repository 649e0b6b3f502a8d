"""The latent-coverage study's rule (README.md): per material, `latent` with coverage weights minus without, from
4,000 random bins and as the five devices' mean at 1,500, with 95 % intervals over the materials; by group and by
pattern (the latent-steps study's tables, another candidate and another rule).

    python research/results/latent-coverage/decide.py OUT            # OUT/families-{random,devices}/compare.json
    python research/results/latent-coverage/decide.py OUT --prefix tables
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "latent-steps"))
import decide as steps  # noqa: E402

steps.CANDIDATE = "latent@coverage_k=32"


def passes(tests: dict) -> bool:
    """Devices' mean above 0, and random bins not wholly below 0."""
    return tests["tables, five devices' mean, psnr"]["low"] > 0 and tests["tables, random bins, psnr"]["high"] >= 0


if __name__ == "__main__":
    raise SystemExit(steps.main(rule=passes, verdicts=("coverage weights in `latent`", "`latent` stays")))
