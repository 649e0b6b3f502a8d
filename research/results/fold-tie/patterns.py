"""fold-tie's exploration after the decision (README.md; decides nothing): `mftie` against real-in-data's `mf` seed-0
runs (trained on an Intel Xeon) through random bins and the five device patterns at 1,500 samples, per measurement
over the 19: the mean change and its 95 % interval, encoder and `latent`, per pattern.

    python research/results/fold-tie/patterns.py OUT/patterns [ARM]   (patterns.sh's readings, fF/compare.json;
                                                                      ARM default mftie)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

BASE = Path(__file__).resolve().parent.parent / "real-in-data" / "out" / "patterns-mf" / "compare.json"


def figures(rows: list[dict], arm: str) -> dict[tuple[str, str, str], float]:
    """(pattern, budget, material) → PSNR of the arm's seed-0 runs."""
    return {(r["pattern"], r["budget"], r["material"]): r["psnr"] for r in rows
            if r["model"].split("/")[0] == arm and r["model"].endswith("-s0")}


def main(out: str, arm: str = "mftie") -> None:
    tied = figures([r for path in sorted(Path(out).glob("f[012]/compare.json"))
                    for r in json.loads(path.read_text())["rows"]], arm)
    base = figures(json.loads(BASE.read_text())["rows"], "mf")
    for budget in ("none", "latent"):
        for pattern in ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "specular"):
            keys = sorted(k for k in tied if k[:2] == (pattern, budget) and k in base)
            d = paired_interval([tied[k] - base[k] for k in keys])
            print(f"{'encoder' if budget == 'none' else budget:7s} {pattern:18s} {arm} {np.mean([tied[k] for k in keys]):.2f}"
                  f"  mf {np.mean([base[k] for k in keys]):.2f}  change {d['mean']:+.2f} [{d['low']:+.2f}, {d['high']:+.2f}]"
                  f" (n {d['n']})")


if __name__ == "__main__":
    main(*sys.argv[1:])
