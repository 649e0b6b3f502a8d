"""full-schedule's rule (README.md), from run.sh's readings.

    python research/results/full-schedule/decide.py OUT

Writes OUT/decision.json and prints the three tests and the figures beside them.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json

BASE, CANDIDATE = "full", "full@schedule=cosine,weight_lr=0.01"


def psnr(out: Path, threads: int, group: str) -> dict[str, dict[tuple[str, str], float]]:
    """Budget → (material, model) → PSNR, of the measurements (``group`` "measured") or the tables."""
    files = sorted((out / f"t{threads}").glob("f*/compare.json")) if group == "measured" else \
        [out / f"t{threads}" / "tables" / "compare.json"]
    figures: dict[str, dict] = {BASE: {}, CANDIDATE: {}}
    for path in files:
        for row in json.loads(path.read_text())["rows"]:
            figures[row["budget"]][row["material"], row["model"]] = row["psnr"]
    return figures


def main(argv: list[str] | None = None) -> int:
    out = Path((argv or sys.argv[1:])[0])
    readings = {(group, threads): psnr(out, threads, group) for group in ("measured", "tables") for threads in (1, 2)}
    change, spread = {}, {}
    for group in ("measured", "tables"):
        one, two = readings[group, 1], readings[group, 2]
        keys = sorted(one[BASE])
        change[group] = paired_interval([one[CANDIDATE][k] - one[BASE][k] for k in keys])
        spread[group] = {budget: sum(abs(two[budget][k] - one[budget][k]) for k in keys) / len(keys)
                         for budget in (BASE, CANDIDATE)}
        spread[group]["keys"] = keys
    both = [(group, k) for group in ("measured", "tables") for k in spread[group].pop("keys")]
    steadier = paired_interval([abs(readings[g, 2][CANDIDATE][k] - readings[g, 1][CANDIDATE][k])
                                - abs(readings[g, 2][BASE][k] - readings[g, 1][BASE][k]) for g, k in both])
    tests = {"a: the 19, candidate − full not wholly below 0": change["measured"]["high"] >= 0,
             "b: the 40 tables, candidate − full not wholly below 0": change["tables"]["high"] >= 0,
             "c: |two threads − one| smaller, interval wholly below 0": steadier["high"] < 0}
    decision = {"tests": tests, "passes": all(tests.values()), "change": change, "spread": spread,
                "steadier": steadier,
                "mean": {f"{group} t{threads} {budget}": sum(v.values()) / len(v)
                         for (group, threads), figures in readings.items() for budget, v in figures.items()}}
    save_json(out / "decision.json", decision)
    for name, passed in tests.items():
        print("pass " if passed else "FAIL ", name)
    for group in ("measured", "tables"):
        c = change[group]
        print(f"{group}: candidate − full {c['mean']:+.2f} dB [{c['low']:+.2f}, {c['high']:+.2f}] (n={c['n']}); "
              f"mean |t2 − t1|: full {spread[group][BASE]:.2f}, candidate {spread[group][CANDIDATE]:.2f}")
    print(f"|t2 − t1| candidate − full, all {steadier['n']}: {steadier['mean']:+.2f} [{steadier['low']:+.2f}, "
          f"{steadier['high']:+.2f}]")
    for key, value in decision["mean"].items():
        print(f"{key}: {value:.2f}")
    print("the rule:", "passes" if decision["passes"] else "fails")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
