"""The seam in tables' truth: a MERL table's step between φ_d = 0.02 and π − 0.02 (across the fold's edge) against
its step between 0.02 and 0.06 (within one side), at random (θ_h, θ_d) on the edge (full-tie's README).

    python research/results/full-tie/truth_seam.py TABLES/nylon.binary TABLES/pink-plastic.binary ...
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from frenbrdf.io.merl import merl_lookup, read_merl
from frenbrdf.models.nbrdf import fold_edge_pairs

FLOOR = 0.01  # seam.py's


def main() -> None:
    pairs = fold_edge_pairs(400, seed=0)
    theta_h = np.arctan2(pairs[:, 0, 0], pairs[:, 0, 2])
    theta_d = np.arctan2(pairs[:, 0, 3], pairs[:, 0, 5])
    for path in map(Path, sys.argv[1:]):
        table = read_merl(path)
        at = {phi: merl_lookup(table, theta_h, theta_d, np.full_like(theta_h, phi)).mean(-1)
              for phi in (0.02, 0.06, np.pi - 0.02)}
        across = np.abs(np.log(at[0.02] + FLOOR) - np.log(at[np.pi - 0.02] + FLOOR))
        within = np.abs(np.log(at[0.02] + FLOOR) - np.log(at[0.06] + FLOOR))
        print(f"{path.stem}: across the edge median {np.median(across):.4f}, p90 {np.quantile(across, 0.9):.4f}; "
              f"within one side median {np.median(within):.4f}")


if __name__ == "__main__":
    main()
