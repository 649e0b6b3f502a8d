"""The latent-anchor study's rule (README.md): per material (measurements: the mean over the three fold
candidates), `latent` with the anchor minus without, through the five device patterns, their mean and each
pattern's, 95 % intervals over the materials; readings with ΔE above 6 counted; by kind on the measurements.

    python research/results/latent-anchor/decide.py OUT     # OUT/{measured,families}/compare.json
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

BASE, CANDIDATE = "latent@coverage_k=32", "latent@coverage_k=32,anchor=0.03"
#: A reading whose ΔE is above this lost the material's hue (issue 48's bound).
HUE_LOST = 6.0


def scores(rows: list[dict], metric: str) -> dict[str, dict[tuple[str, str], float]]:
    """``{budget: {(pattern, material): metric}}``, the mean over the models that read each."""
    runs: dict[tuple[str, str, str], list[float]] = defaultdict(list)
    for row in rows:
        if row["group"] in ("measured", "tables"):  # the kinds' groups repeat these rows
            runs[row["budget"], row["pattern"], row["material"]].append(row[metric])
    out: dict[str, dict[tuple[str, str], float]] = defaultdict(dict)
    for (budget, pattern, material), values in runs.items():
        out[budget][pattern, material] = float(np.mean(values))
    return out


def hue_lost(rows: list[dict], budget: str) -> int:
    return sum(row["delta_e"] > HUE_LOST for row in rows
               if row["budget"] == budget and row["group"] in ("measured", "tables"))


def text(test: dict) -> str:
    return f"{test['mean']:+.2f} [{test['low']:+.2f}, {test['high']:+.2f}] (n {test['n']})"


def tests(rows: list[dict], kinds: dict[str, list[str]] | None = None) -> dict[str, dict]:
    """Every interval of one set: the five devices' mean, each pattern, and (measurements) each kind's mean."""
    found = {}
    for metric in ("psnr", "delta_e"):
        by_budget = scores(rows, metric)
        difference = {key: by_budget[CANDIDATE][key] - value for key, value in by_budget[BASE].items()}
        patterns = sorted({pattern for pattern, _ in difference})
        materials = sorted({material for _, material in difference})
        per_material = {m: np.mean([difference[p, m] for p in patterns]) for m in materials}
        found[f"five devices' mean, {metric}"] = paired_interval(list(per_material.values()))
        for pattern in patterns:
            found[f"{pattern}, {metric}"] = paired_interval([difference[pattern, m] for m in materials])
        for kind, names in (kinds or {}).items():
            found[f"kind {kind}, {metric}"] = paired_interval([per_material[m] for m in materials if m in names])
    return found


def main(out: Path) -> int:
    folds = json.loads((Path(__file__).resolve().parents[2] / "studies/measured_folds/folds.json").read_text())
    results = {}
    for name in ("families", "measured"):
        rows = json.loads((out / name / "compare.json").read_text())["rows"]
        results[name] = tests(rows, folds["kinds"] if name == "measured" else None)
        for label, test in results[name].items():
            print(f"{name}, {label}: {text(test)}")
        print(f"{name}, readings with ΔE > {HUE_LOST:g}: {hue_lost(rows, BASE)} without the anchor, "
              f"{hue_lost(rows, CANDIDATE)} with it")
        results[name]["hue lost"] = (hue_lost(rows, BASE), hue_lost(rows, CANDIDATE))
    lands = (results["families"]["five devices' mean, psnr"]["high"] >= 0
             and results["measured"]["five devices' mean, psnr"]["high"] >= 0
             and results["measured"]["hue lost"][1] < results["measured"]["hue lost"][0])
    print(f"rule: {'the anchor on where a device took the samples' if lands else 'the anchor stays off'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1])))
