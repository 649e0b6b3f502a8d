"""The latent-native study's rule (README.md): per material, `latent` at 1,200 steps minus at 600, with 95 %
intervals over the materials: on the families and the held-out tables from 4,000 random bins and as the five
devices' mean at 1,500 (the rule's tests), and on the 19 measurements by their fold runs (reported: the means of
each budget, by kind, and the readings that lose a material's hue).

    python research/results/latent-native/decide.py OUT   # OUT/{families,tables}-{random,devices}, OUT/measured
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from budget_readings import judged, measured  # noqa: E402

BASE, CANDIDATE = "latent", "latent@latent_steps=1200"


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        sys.exit(__doc__)
    out = Path(argv[0])
    families = judged(out, "families", BASE, CANDIDATE)
    tables = judged(out, "tables", BASE, CANDIDATE)
    passed = (families["random psnr"]["low"] > 0 and families["devices psnr"]["high"] > 0
              and tables["random psnr"]["high"] > 0)
    print(f"rule (a)–(c): {'1,200 steps' if passed else '600 steps stay'}")
    if (out / "measured" / "compare.json").exists():
        measured(out, ["none", BASE, CANDIDATE], BASE, CANDIDATE)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
