"""The report's tables by kind (README.md): the `fits` runs' PSNR / ΔE per kind and pattern, each material the
mean of the three seeds, then the kind's mean; and each pattern's worst material.

    python research/results/patterns-measured/by_kind.py local/pm/encoder/compare.json 1500
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

PATTERNS = ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "specular")
FOLDS = Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json"


def main() -> None:
    rows = json.loads(Path(sys.argv[1]).read_text())["rows"]
    count = int(sys.argv[2])
    kinds = json.loads(FOLDS.read_text())["kinds"]
    per_material: dict[tuple[str, str], list[tuple[float, float]]] = defaultdict(list)
    for r in rows:
        if r["model"].startswith("fits") and r["group"] == "measured" and r["count"] == count:
            per_material[r["pattern"], r["material"]].append((r["psnr"], r["delta_e"]))
    means = {key: np.mean(values, axis=0) for key, values in per_material.items()}
    print("| kind | " + " | ".join(PATTERNS) + " |")
    print("|---|" + "---|" * len(PATTERNS))
    for kind, materials in [*kinds.items(), ("all 19", [m for ms in kinds.values() for m in ms])]:
        cells = [np.mean([means[p, m] for m in materials], axis=0) for p in PATTERNS]
        print(f"| {kind} | " + " | ".join(f"{psnr:.1f} / {de:.1f}" for psnr, de in cells) + " |")
    for p in PATTERNS:
        worst = min((m for q, m in means if q == p), key=lambda m: means[p, m][0])
        print(f"worst through {p}: {worst} {means[p, worst][0]:.1f} dB / ΔE {means[p, worst][1]:.1f}")


if __name__ == "__main__":
    main()
