"""Per pattern, each variant's `latent` PSNR minus the baseline's, per material, with a 95 % t-interval; ΔE likewise.

    python research/results/display-weights/summarise.py BASELINE VARIANT...   (folders holding compare.json)
"""

from __future__ import annotations

import json
import sys

import numpy as np
from scipy import stats


def readings(folder: str) -> dict[tuple, tuple[float, float]]:
    rows = json.loads(open(f"{folder}/compare.json").read())["rows"]
    return {(r["material"], r["pattern"], r["count"]): (r["psnr"], r["delta_e"]) for r in rows if r["budget"] != "none"}


def main() -> None:
    baseline, *variants = sys.argv[1:]
    base = readings(baseline)
    conditions = sorted({key[1:] for key in base})
    for variant in variants:
        other = readings(variant)
        print(f"{variant} − {baseline}")
        for condition in conditions:
            keys = [key for key in base if key[1:] == condition and key in other]
            psnr = np.array([other[key][0] - base[key][0] for key in keys])
            delta_e = np.array([other[key][1] - base[key][1] for key in keys])
            half = stats.t.ppf(0.975, len(psnr) - 1) * psnr.std(ddof=1) / np.sqrt(len(psnr))
            print(f"  {condition[0]:20s} {np.mean([base[key][0] for key in keys]):6.2f} dB  "
                  f"{psnr.mean():+.2f} [{psnr.mean() - half:+.2f}, {psnr.mean() + half:+.2f}]  ΔE {delta_e.mean():+.2f}")


if __name__ == "__main__":
    main()
