"""Two refinement budgets read by ``compare_models.py`` on the same samples, compared per material: the helpers of the
studies that decide a budget's setting (latent-native, latent-rate). A reading folder holds ``compare.json``; the
judged sets are read twice, ``PREFIX-random`` (4,000 random bins) and ``PREFIX-devices`` (the five device patterns),
and the measurements once, ``measured`` (each by the fold run that did not train on it).
"""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

#: A reading whose ΔE is above this lost the material's hue (issue 48's bound).
HUE_LOST = 6.0
#: The measurements' kinds, by the folds' file.
FOLDS = Path(__file__).resolve().parent / "measured_folds" / "folds.json"


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


def changes(rows: list[dict], metric: str, group: str, base: str, candidate: str) -> dict[str, dict[str, float]]:
    """``{pattern: {material: candidate − base}}``."""
    scores = by_budget(rows, metric, group)
    out: dict[str, dict[str, float]] = defaultdict(dict)
    for (pattern, material), value in scores[candidate].items():
        out[pattern][material] = value - scores[base][pattern, material]
    return out


def plain_group(rows: list[dict]) -> str:
    """The group of a reading's materials (not one of its ``GROUP @ PATTERN × COUNT`` summaries)."""
    return {row["group"] for row in rows if "@" not in row["group"]}.pop()


def devices_mean(per_pattern: dict[str, dict[str, float]]) -> dict[str, float]:
    """``{material: the change averaged over the device patterns}`` of :func:`changes`' ``{pattern: {material:
    change}}``, over the materials every pattern read."""
    materials = sorted(set.intersection(*(set(p) for p in per_pattern.values())))
    return {m: float(np.mean([p[m] for p in per_pattern.values()])) for m in materials}


def judged(out: Path, prefix: str, base: str, candidate: str) -> dict[str, dict]:
    """Every test on one judged set (families or tables), printed; returns ``{"random psnr": interval, "devices
    psnr": ..., and the same for delta_e}``."""
    random, devices = rows_of(out / f"{prefix}-random"), rows_of(out / f"{prefix}-devices")
    tests = {}
    for metric in ("psnr", "delta_e"):
        for _pattern, by_material in changes(random, metric, plain_group(random), base, candidate).items():
            print(f"{prefix}, random bins, {metric}: {interval_text(list(by_material.values()))}")
            tests[f"random {metric}"] = paired_interval(list(by_material.values()))
        per_pattern = changes(devices, metric, plain_group(devices), base, candidate)
        mean = list(devices_mean(per_pattern).values())
        print(f"{prefix}, five devices' mean, {metric}: {interval_text(mean)}")
        tests[f"devices {metric}"] = paired_interval(mean)
        for pattern, by_material in sorted(per_pattern.items()):
            print(f"{prefix}, {pattern}, {metric}: {interval_text(list(by_material.values()))}")
    return tests


def measured(out: Path, budgets: list[str], base: str, candidate: str) -> dict:
    """The measurements by their fold runs, printed: each budget's mean, by kind, the change per measurement and
    the readings that lose a material's hue; returns the PSNR change's interval."""
    rows = rows_of(out / "measured")
    kinds = json.loads(FOLDS.read_text())["kinds"]
    psnr, delta_e = by_budget(rows, "psnr", "measured"), by_budget(rows, "delta_e", "measured")

    def mean(scores: dict, names: list[str] | None) -> float:
        return float(np.mean([v for (_, m), v in scores.items() if names is None or m in names]))

    for kind, names in {"all 19": None, **kinds}.items():
        print(f"{kind}: " + "  ".join(f"{budget} {mean(psnr[budget], names):.2f} / {mean(delta_e[budget], names):.2f}"
                                      for budget in budgets))
    change = {metric: list(changes(rows, metric, "measured", base, candidate)["merl-bins"].values())
              for metric in ("psnr", "delta_e")}
    for metric, values in change.items():
        print(f"measured, random bins, {metric}: {interval_text(values)}")
    for budget, scores in delta_e.items():
        lost = {material: round(value, 2) for (_, material), value in scores.items() if value > HUE_LOST}
        print(f"ΔE > {HUE_LOST:g} with {budget}: {lost or 'none'}")
    return paired_interval(change["psnr"])
