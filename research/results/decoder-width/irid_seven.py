"""decoder-width's exploration (README.md): `irid_flake_paint2` read by a decoder trained on seven measurements only
(it among them), from its last checkpoint: encoder, `latent` and `full` beside the truth (latent-size's
irid_trained.py, one row); 4,000 random valid bins, draw 0.

    python research/results/decoder-width/irid_seven.py CHECKPOINT research/results/decoder-width/irid-seven.jpg
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "latent-size"))
from irid_trained import save_irid_rows  # noqa: E402

if __name__ == "__main__":
    save_irid_rows({"seven": sys.argv[1]}, sys.argv[2])
