"""hue-shift's second comparison (README.md; decides nothing): `mfshift` against the recipe's seed-0 fold runs trained
again on this same machine (latent-native's readings of them), per measurement over the 19: the mean paired
difference and its 95 % t interval, encoder and `latent`, PSNR and ΔE.

    python research/results/hue-shift/against_here.py research/results/latent-native/out/measured/compare.json \
        research/results/hue-shift/out/mfshift-f*-s0/compare.json
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from budget_readings import interval_text, rows_of  # noqa: E402


def readings(paths: list[str]) -> dict[tuple[str, str], tuple[float, float]]:
    """(material, budget) → (PSNR, ΔE) of the readings in compare.json files."""
    return {(row["material"], row["budget"]): (row["psnr"], row["delta_e"])
            for path in paths for row in rows_of(Path(path).parent)}


def main(base_path: str, new_paths: list[str]) -> None:
    base, new = readings([base_path]), readings(new_paths)
    for budget in ("none", "latent"):
        materials = sorted(m for (m, b) in base if b == budget and (m, b) in new)
        for i, metric in enumerate(("PSNR", "ΔE")):
            change = [new[m, budget][i] - base[m, budget][i] for m in materials]
            print(f"{budget:6s} {metric:4s} here {np.mean([base[m, budget][i] for m in materials]):.2f}"
                  f"  mfshift {np.mean([new[m, budget][i] for m in materials]):.2f}  change {interval_text(change)}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
