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
#: The base's name in run.sh's readings: `full` in those made before `full` took the candidate's schedule.
BASE_NAMES = ("full", "full@schedule=constant,weight_lr=0.003")


def psnr(out: Path, threads: int, group: str) -> dict[str, dict[tuple[str, str], float]]:
    """BASE or CANDIDATE → (material, model) → PSNR, of the measurements (``group`` "measured") or the tables."""
    files = sorted((out / f"t{threads}").glob("f*/compare.json")) if group == "measured" else \
        [out / f"t{threads}" / "tables" / "compare.json"]
    figures: dict[str, dict] = {BASE: {}, CANDIDATE: {}}
    for path in files:
        for row in json.loads(path.read_text())["rows"]:
            budget = BASE if row["budget"] in BASE_NAMES else row["budget"]
            figures[budget][row["material"], row["model"]] = row["psnr"]
    return figures


def main(argv: list[str] | None = None) -> int:
    out = Path((argv or sys.argv[1:])[0])
    readings = {(group, threads): psnr(out, threads, group) for group in ("measured", "tables") for threads in (1, 2)}
    def moved(group: str, budget: str, key) -> float:  # |two threads − one thread|
        return abs(readings[group, 2][budget][key] - readings[group, 1][budget][key])

    keys = {group: sorted(readings[group, 1][BASE]) for group in ("measured", "tables")}
    change = {group: paired_interval([readings[group, 1][CANDIDATE][k] - readings[group, 1][BASE][k] for k in ks])
              for group, ks in keys.items()}
    spread = {group: {budget: sum(moved(group, budget, k) for k in ks) / len(ks) for budget in (BASE, CANDIDATE)}
              for group, ks in keys.items()}
    steadier = paired_interval([moved(g, CANDIDATE, k) - moved(g, BASE, k) for g, ks in keys.items() for k in ks])
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
