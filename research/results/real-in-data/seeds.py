"""The amendment's figures (README.md): each measurement's `mf` figure the mean of the seeds its fold has, over the
19, per budget; and each run's own mean over its fold's measurements (the seed-to-seed spread).

    python research/results/real-in-data/seeds.py OUT/measured/compare.json SEEDS/*/compare.json
"""

import collections
import json
import sys

import numpy as np


def main(paths: list[str]) -> None:
    rows = [r for path in paths for r in json.load(open(path))["rows"] if r["model"].startswith("mf/")]
    runs = sorted({r["model"] for r in rows})
    print("runs", runs)
    for budget in ("none", "latent", "full"):
        per = collections.defaultdict(list)
        for r in rows:
            if r["budget"] == budget:
                per[r["material"]].append((r["psnr"], r["delta_e"]))
        psnr = np.mean([np.mean([x[0] for x in v]) for v in per.values()])
        delta_e = np.mean([np.mean([x[1] for x in v]) for v in per.values()])
        worst = max(per, key=lambda m: np.mean([x[1] for x in per[m]]))
        print(f"{budget}: {len(per)} measurements, PSNR {psnr:.2f}, ΔE {delta_e:.2f}; "
              f"worst ΔE {worst} {np.mean([x[1] for x in per[worst]]):.2f}")
        for run in runs:
            mine = [r for r in rows if r["model"] == run and r["budget"] == budget]
            print(f"   {run}: {len(mine)} measurements, PSNR {np.mean([r['psnr'] for r in mine]):.2f}, "
                  f"ΔE {np.mean([r['delta_e'] for r in mine]):.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])
