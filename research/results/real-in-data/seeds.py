"""The amendment's figures (README.md): each measurement's figure per arm the mean of the seeds its fold has, over
the 19 and by kind, per budget; each run's own mean over its fold's measurements (the seed-to-seed spread); and,
given folds-v8's reading (its `v4` and `v8` runs, three seeds a fold, the same draws), the per-measurement
differences `mf − v4` and `mf − v8` with their 95 % intervals.

    python research/results/real-in-data/seeds.py OUT/measured/compare.json SEEDS/*/compare.json \\
        [--baselines research/results/folds-v8/measured/compare.json]
"""

from __future__ import annotations

import argparse
import collections
import json
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

KINDS = json.loads((Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json").read_text())["kinds"]
BUDGETS = ("none", "latent", "full")


def per_material(rows: list[dict], arm: str, budget: str) -> dict[str, tuple[float, float, int]]:
    """Material → (PSNR, ΔE, runs): the arm's mean over its runs that scored the material."""
    per = collections.defaultdict(list)
    for r in rows:
        if r["model"].split("/")[0] == arm and r["budget"] == budget:
            per[r["material"]].append((r["psnr"], r["delta_e"]))
    return {m: (float(np.mean([v[0] for v in values])), float(np.mean([v[1] for v in values])), len(values))
            for m, values in per.items()}


def mean(figures: dict, names) -> str:
    names = [n for n in names if n in figures]
    return f"{np.mean([figures[n][0] for n in names]):.2f} / {np.mean([figures[n][1] for n in names]):.2f}"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("compare", nargs="+", help="compare_models.py outputs holding `mf/fF-sS` rows")
    parser.add_argument("--baselines", nargs="*", default=[], help="outputs holding `v4/sS` and `v8/sS` rows")
    args = parser.parse_args(argv)
    rows = [r for path in args.compare for r in json.load(open(path))["rows"] if r["model"].startswith("mf/")]
    baseline_rows = [r for path in args.baselines for r in json.load(open(path))["rows"] if r["group"] == "measured"]
    arms = ["mf", *sorted({r["model"].split("/")[0] for r in baseline_rows} & {"v4", "v8"})]
    print("runs", sorted({r["model"] for r in rows}))
    for budget in BUDGETS:
        figures = {"mf": per_material(rows, "mf", budget)}
        figures |= {arm: per_material(baseline_rows, arm, budget) for arm in arms[1:]}
        mf = figures["mf"]
        worst = max(mf, key=lambda m: mf[m][1])
        seeds = sorted({n for _, _, n in mf.values()})
        print(f"\n{budget}: {len(mf)} measurements ({'/'.join(map(str, seeds))} runs each), "
              + "; ".join(f"{arm} {mean(figures[arm], mf)}" for arm in arms) + f"; worst ΔE ({'mf'}) {worst} {mf[worst][1]:.2f}")
        for arm in arms[1:]:
            both = sorted(mf.keys() & figures[arm].keys())
            interval = paired_interval([mf[m][0] - figures[arm][m][0] for m in both])
            print(f"   mf − {arm}, PSNR per measurement ({len(both)}): {interval['mean']:+.2f} "
                  f"[{interval['low']:+.2f}, {interval['high']:+.2f}]")
        print("   by kind: " + "; ".join(f"{kind} " + ", ".join(f"{arm} {mean(figures[arm], names)}" for arm in arms)
                                     for kind, names in KINDS.items()))
        for run in sorted({r["model"] for r in rows}):
            mine = [r for r in rows if r["model"] == run and r["budget"] == budget]
            print(f"   {run}: {len(mine)} measurements, PSNR {np.mean([r['psnr'] for r in mine]):.2f}, "
                  f"ΔE {np.mean([r['delta_e'] for r in mine]):.2f}")


if __name__ == "__main__":
    main()
