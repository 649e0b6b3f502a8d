"""The decision of research/results/diffractive, by the rule fixed before its runs (README.md).

    python research/results/diffractive/decide.py OUT COMPARE.json...

COMPARE.json: `compare_models.py` outputs holding rows of both arms, `mf/fF-sS` and `mfd/fF-sS` (the measurements
by the runs of their own fold; the 40 held-out tables, group ``tables``). The rule: the bank ships if (a)
`irid_flake_paint2`'s ΔE with `latent`, `mfd − mf` over their fold-1 runs, has its 95 % Welch interval below 0,
(b) over the 19 measurements the per-measurement encoder PSNR `mfd − mf` (each arm the mean of its runs) has its
interval not wholly below 0, and (c) the same on the 40 tables. A part whose rows are not all there yet is
reported as not read; the decision is "does not ship" as soon as one part fails. Writes OUT/decision.json.
"""

from __future__ import annotations

import collections
import json
import sys
from pathlib import Path

import numpy as np
from scipy import stats

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json

IRIDESCENT = "irid_flake_paint2_rgb"
ARMS = ("mf", "mfd")
SEEDS = 3
MEASUREMENTS, TABLES = 19, 40


def welch_interval(new: list[float], old: list[float], confidence: float = 0.95) -> dict:
    """Mean of ``new`` less mean of ``old``, with Welch's t-interval (unequal variances)."""
    test = stats.ttest_ind(new, old, equal_var=False)
    interval = test.confidence_interval(confidence)
    return {"mean": float(np.mean(new) - np.mean(old)), "low": float(interval.low), "high": float(interval.high),
            "n": [len(new), len(old)]}


def runs(rows: list[dict], arm: str) -> set[str]:
    return {r["model"] for r in rows if r["model"].split("/")[0] == arm}


def rule_a(rows: list[dict]) -> dict:
    """`irid_flake_paint2`'s `latent` ΔE per fold-1 run of each arm, and the difference's Welch interval."""
    per_arm = {arm: [r["delta_e"] for r in rows if r["model"].startswith(f"{arm}/f1-") and r["budget"] == "latent"
                     and r["material"] == IRIDESCENT] for arm in ARMS}
    part = {"delta_e": per_arm}
    if min(len(v) for v in per_arm.values()) < SEEDS:
        return part | {"read": False}
    interval = welch_interval(per_arm["mfd"], per_arm["mf"])
    return part | {"read": True, "difference": interval, "holds": interval["high"] < 0}


def rule_paired(rows: list[dict], group: str, expected: int) -> dict:
    """Encoder PSNR `mfd − mf` per material of ``group`` (each arm the mean of its runs): not wholly below 0."""
    mine = [r for r in rows if r["group"] == group and r["budget"] == "none"]
    means = {}
    for arm in ARMS:
        per = collections.defaultdict(list)
        for r in mine:
            if r["model"].split("/")[0] == arm:
                per[r["material"]].append(r["psnr"])
        means[arm] = {m: float(np.mean(v)) for m, v in per.items() if len(v) >= SEEDS}
    both = sorted(means["mf"].keys() & means["mfd"].keys())
    part = {"materials": len(both)}
    if len(both) < expected:
        return part | {"read": False}
    interval = paired_interval([means["mfd"][m] - means["mf"][m] for m in both])
    return part | {"read": True, "difference": interval, "holds": interval["high"] >= 0}


def main(out: Path, paths: list[Path]) -> None:
    rows = [r for path in paths for r in json.loads(path.read_text())["rows"]]
    rules = {"a": rule_a(rows), "b": rule_paired(rows, "measured", MEASUREMENTS),
             "c": rule_paired(rows, "tables", TABLES)}
    if any(part["read"] and not part["holds"] for part in rules.values()):
        decision = "the diffractive bank does not ship"
    elif all(part["read"] for part in rules.values()):
        decision = "the diffractive bank ships"
    else:
        decision = "not decided: parts not read yet"
    result = {"runs": {arm: sorted(runs(rows, arm)) for arm in ARMS}, "rules": rules, "decision": decision}
    save_json(out / "decision.json", result)
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(Path(sys.argv[1]), [Path(p) for p in sys.argv[2:]])
