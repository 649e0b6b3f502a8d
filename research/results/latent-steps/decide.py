"""The latent-steps study's rule (README.md): per material, `latent` at 600 steps minus at 200, from 4,000 random
bins and as the five devices' mean at 1,500, with 95 % intervals over the materials; by group (families or tables,
measured) and by pattern.

    python research/results/latent-steps/decide.py OUT            # OUT/families-{random,devices}/compare.json
    python research/results/latent-steps/decide.py OUT --prefix tables
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

BASE, CANDIDATE = "latent", "latent@latent_steps=600"


def differences(rows: list[dict], metric: str) -> dict[tuple[str, str], dict[str, float]]:
    """``{(group, pattern): {material: candidate − base}}``."""
    scores = {(r["group"], r["pattern"], r["material"], r["budget"]): r[metric] for r in rows}
    out: dict[tuple[str, str], dict[str, float]] = defaultdict(dict)
    for (group, pattern, material, budget), value in scores.items():
        if budget == CANDIDATE:
            out[group, pattern][material] = value - scores[group, pattern, material, BASE]
    return out


def interval_text(d: dict) -> str:
    return f"{d['mean']:+.2f} [{d['low']:+.2f}, {d['high']:+.2f}] (n {d['n']})"


def steps_rule(tests: dict) -> bool:
    """This study's rule: random bins above 0, and the devices' mean not wholly below 0."""
    return tests["tables, random bins, psnr"]["low"] > 0 and tests["tables, five devices' mean, psnr"]["high"] > 0


def main(argv=None, rule=steps_rule, verdicts=("600 steps", "200 steps stay")) -> int:
    """Prints every test; on the families, the verdict of ``rule`` (another study passes its own rule)."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path)
    parser.add_argument("--prefix", default="families")
    args = parser.parse_args(argv)
    random, devices = (json.loads((args.out / f"{args.prefix}-{kind}" / "compare.json").read_text())["rows"]
                       for kind in ("random", "devices"))
    tests = {}
    for metric in ("psnr", "delta_e"):
        for (group, _pattern), by_material in differences(random, metric).items():
            tests[f"{group}, random bins, {metric}"] = paired_interval(list(by_material.values()))
        per_pattern = differences(devices, metric)
        for group in sorted({group for group, _ in per_pattern}):
            patterns = [by_material for (g, _), by_material in per_pattern.items() if g == group]
            materials = sorted(set.intersection(*(set(p) for p in patterns)))
            tests[f"{group}, five devices' mean, {metric}"] = paired_interval(
                [np.mean([p[m] for p in patterns]) for m in materials])
            for (g, pattern), by_material in per_pattern.items():
                if g == group:
                    tests[f"{group}, {pattern}, {metric}"] = paired_interval(list(by_material.values()))
    for name, test in tests.items():
        print(f"{name}: {interval_text(test)}")
    if args.prefix == "families":  # the families are read as tables
        print(f"rule: {verdicts[0] if rule(tests) else verdicts[1]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
