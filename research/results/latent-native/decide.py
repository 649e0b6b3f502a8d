"""The latent-native study's rule (README.md): per material, `latent` at 1,200 steps minus at 600, with 95 %
intervals over the materials: on the families and the held-out tables from 4,000 random bins and as the five
devices' mean at 1,500 (the rule's tests), and on the 19 measurements by their fold runs (reported: the means of
each budget, by kind, and the readings that lose a material's hue).

    python research/results/latent-native/decide.py OUT   # OUT/{families,tables}-{random,devices}, OUT/measured
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

BASE, CANDIDATE = "latent", "latent@latent_steps=1200"
#: A reading whose ΔE is above this lost the material's hue (issue 48's bound).
HUE_LOST = 6.0


def rows_of(path: Path) -> list[dict]:
    return json.loads((path / "compare.json").read_text())["rows"]


def by_budget(rows: list[dict], metric: str, group: str) -> dict[str, dict[tuple[str, str], float]]:
    """``{budget: {(pattern, material): metric}}`` over the rows of ``group``."""
    out: dict[str, dict[tuple[str, str], float]] = defaultdict(dict)
    for row in rows:
        if row["group"] == group:
            out[row["budget"]][row.get("pattern", "merl-bins"), row["material"]] = row[metric]
    return out


def interval_text(values: list[float]) -> str:
    d = paired_interval(values)
    return f"{d['mean']:+.2f} [{d['low']:+.2f}, {d['high']:+.2f}] (n {d['n']})"


def changes(rows: list[dict], metric: str, group: str) -> dict[str, dict[str, float]]:
    """``{pattern: {material: candidate − base}}``."""
    scores = by_budget(rows, metric, group)
    out: dict[str, dict[str, float]] = defaultdict(dict)
    for (pattern, material), value in scores[CANDIDATE].items():
        out[pattern][material] = value - scores[BASE][pattern, material]
    return out


def judged(out: Path, prefix: str) -> dict[str, dict]:
    """Every test on one judged set (families or tables), printed; returns the rule's three."""
    random, devices = rows_of(out / f"{prefix}-random"), rows_of(out / f"{prefix}-devices")
    group = {row["group"] for row in random}.pop()
    tests = {}
    for metric in ("psnr", "delta_e"):
        for _pattern, by_material in changes(random, metric, group).items():
            print(f"{prefix}, random bins, {metric}: {interval_text(list(by_material.values()))}")
            tests[f"random {metric}"] = paired_interval(list(by_material.values()))
        per_pattern = changes(devices, metric, {row["group"] for row in devices if "@" not in row["group"]}.pop())
        materials = sorted(set.intersection(*(set(p) for p in per_pattern.values())))
        mean = [float(np.mean([p[m] for p in per_pattern.values()])) for m in materials]
        print(f"{prefix}, five devices' mean, {metric}: {interval_text(mean)}")
        tests[f"devices {metric}"] = paired_interval(mean)
        for pattern, by_material in sorted(per_pattern.items()):
            print(f"{prefix}, {pattern}, {metric}: {interval_text(list(by_material.values()))}")
    return tests


def measured(out: Path) -> None:
    """The 19 by their fold runs: each budget's mean, the change per measurement, by kind, hue lost."""
    rows = rows_of(out / "measured")
    kinds = json.loads((Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json")
                       .read_text())["kinds"]
    psnr, delta_e = by_budget(rows, "psnr", "measured"), by_budget(rows, "delta_e", "measured")
    def mean(scores: dict, names: list[str] | None) -> float:
        return float(np.mean([v for (_, m), v in scores.items() if names is None or m in names]))

    for kind, names in {"all 19": None, **kinds}.items():
        print(f"{kind}: " + "  ".join(f"{budget} {mean(psnr[budget], names):.2f} / {mean(delta_e[budget], names):.2f}"
                                      for budget in ("none", BASE, CANDIDATE)))
    for metric in ("psnr", "delta_e"):
        print(f"measured, random bins, {metric}: "
              f"{interval_text(list(changes(rows, metric, 'measured')['merl-bins'].values()))}")
    for budget, scores in by_budget(rows, "delta_e", "measured").items():
        lost = {material: round(value, 2) for (_, material), value in scores.items() if value > HUE_LOST}
        print(f"ΔE > {HUE_LOST:g} with {budget}: {lost or 'none'}")


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        sys.exit(__doc__)
    out = Path(argv[0])
    families = judged(out, "families")
    tables = judged(out, "tables")
    passed = (families["random psnr"]["low"] > 0 and families["devices psnr"]["high"] > 0
              and tables["random psnr"]["high"] > 0)
    print(f"rule (a)–(c): {'1,200 steps' if passed else '600 steps stay'}")
    if (out / "measured" / "compare.json").exists():
        measured(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
