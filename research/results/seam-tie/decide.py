"""The seam-tie study's rule (README.md): paired PSNR and ΔE differences tied − fold, and the seam steps.

    python research/results/seam-tie/decide.py WORK [--arm tied|tied@0.3] [--json FILE]
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from paired_arms import decide  # noqa: E402


def removes_seam(seam: dict, arm: str) -> bool:
    """The arm's median step at most a quarter of fold's for the encoder and `latent`."""
    return all(seam[arm][budget]["median"] <= seam["fold"][budget]["median"] / 4 for budget in ("none", "latent"))


if __name__ == "__main__":
    decide(__doc__.split("\n\n")[0], "tied", ("none", "latent", "full"), removes_seam)
