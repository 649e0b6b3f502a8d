"""The doubled-φ_d study's rule (README.md): paired PSNR and ΔE differences arm − fold, and the seam steps.

    python research/results/doubled-phi-d/decide.py WORK [--arm doubled|scaled] [--json FILE]
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from paired_arms import decide  # noqa: E402


def removes_seam(seam: dict, arm: str) -> bool:
    """The arm's median step below 0.001 for the encoder and `latent`."""
    return all(seam[arm][budget]["median"] < 0.001 for budget in ("none", "latent"))


if __name__ == "__main__":
    decide(__doc__.split("\n\n")[0], "doubled", ("none", "latent"), removes_seam)
