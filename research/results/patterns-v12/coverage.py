"""patterns-v12's coverage readings (README.md): `latent` with the coverage weights (`coverage_k=32`) against plain
`latent`, per table and pattern and count (coverage.txt); or, with ``--families``, the in-plane check on the 45
families of seed 24 and its rule (families24.txt).

    python research/results/patterns-v12/coverage.py OUT   (OUT holds merl-bins/, gonioreflectometer/, coverage-*/)
    python research/results/patterns-v12/coverage.py OUT --families   (OUT holds families24/)
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

COVERED = "latent@coverage_k=32"
DEVICES = ("uniform", "in-plane", "gonioreflectometer", "image-based", "specular")


def readings(folders: list[Path]) -> dict[tuple[str, str, int], dict[str, float]]:
    """(budget, pattern, count) → {material: PSNR}, the per-material rows only."""
    table: dict[tuple[str, str, int], dict[str, float]] = {}
    for folder in folders:
        for row in json.loads((folder / "compare.json").read_text())["rows"]:
            if "@" not in row["group"]:
                table.setdefault((row["budget"], row["pattern"], row["count"]), {})[row["material"]] = row["psnr"]
    return table


def change(table: dict, key: tuple[str, int]) -> dict:
    covered, plain = table[(COVERED, *key)], table[("latent", *key)]
    return paired_interval([covered[m] - plain[m] for m in covered])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--families", action="store_true")
    args = parser.parse_args()
    if args.families:
        table = readings([args.out / "families24"])
        d = change(table, ("in-plane", 1500))
        print(f"45 families (seed 24), 1,500 in-plane pairs, draw 0: latent "
              f"{np.mean(list(table[('latent', 'in-plane', 1500)].values())):.2f}, with coverage "
              f"{np.mean(list(table[(COVERED, 'in-plane', 1500)].values())):.2f}; coverage − plain {d['mean']:+.2f} "
              f"[{d['low']:+.2f}, {d['high']:+.2f}] (n {d['n']})")
        print("rule: stop the weights for in-plane pairs:", d["high"] < 0)
        return
    table = readings(sorted(path.parent for path in args.out.glob("*/compare.json") if path.parent.name != "families24"))
    for pattern in DEVICES:
        for count in (300, 1500, 4000):
            d = change(table, (pattern, count))
            print(f"{pattern:18s} {count:5d} coverage − plain {d['mean']:+.2f} [{d['low']:+.2f}, {d['high']:+.2f}]")


if __name__ == "__main__":
    main()
