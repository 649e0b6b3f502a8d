"""The figures of research/results/folds-v8 against issue 48's goals, from evaluate.sh's two compare.json.

    python research/results/folds-v8/summarise.py OUT     # writes OUT/goals.md and OUT/goals.json

Per arm (`v4`, `v8`: each material's PSNR / ΔE the mean over the arm's three runs) and budget: the mean over the
19 measurements, by kind, the materials whose ΔE exceeds 6, and `v8 − v4` per measurement with its 95 % interval;
the same difference on the 40 held-out tables; where OUT holds evaluate_patterns.sh's two folders, each pattern's
figures of both arms and their difference. Reported, not decided (the README).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json, write_text

ARMS = ("v4", "v8")
BUDGETS = ("none", "latent", "full")
#: Issue 48's goals on measurements outside training: PSNR at least, ΔE at most.
GOALS = {"none": (30.0, 3.0), "latent": (35.0, 1.5), "full": (38.0, 1.0)}
HUE_LOST = 6.0
FOLDS = Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json"


def per_material(rows: list[dict], arm: str, budget: str, metric: str) -> dict[str, float]:
    """Material → the arm's metric at ``budget``, the mean over its runs."""
    mine = [r for r in rows if r["model"].split("/")[0] == arm and r["budget"] == budget]
    return {m: float(np.mean([r[metric] for r in mine if r["material"] == m]))
            for m in sorted({r["material"] for r in mine})}


def summarise(measured: dict, tables: dict) -> dict:
    rows, kinds = measured["rows"], json.loads(FOLDS.read_text())["kinds"]
    out = {"arms": {}, "v8 - v4": {}, "tables v8 - v4": {}}
    for arm in ARMS:
        out["arms"][arm] = {}
        for budget in BUDGETS:
            psnr, delta_e = per_material(rows, arm, budget, "psnr"), per_material(rows, arm, budget, "delta_e")
            goal_psnr, goal_delta_e = GOALS[budget]
            out["arms"][arm][budget] = {
                "psnr": float(np.mean(list(psnr.values()))), "delta_e": float(np.mean(list(delta_e.values()))),
                "meets_goal": bool(np.mean(list(psnr.values())) >= goal_psnr
                                   and np.mean(list(delta_e.values())) <= goal_delta_e),
                "hue_lost": {m: round(d, 2) for m, d in delta_e.items() if d > HUE_LOST},
                "by_kind": {kind: [float(np.mean([psnr[m] for m in names if m in psnr])),
                                   float(np.mean([delta_e[m] for m in names if m in delta_e]))]
                            for kind, names in kinds.items()},
            }
    for budget in BUDGETS:
        new, old = per_material(rows, "v8", budget, "psnr"), per_material(rows, "v4", budget, "psnr")
        out["v8 - v4"][budget] = paired_interval([new[m] - old[m] for m in new])
    for budget in ("none", "latent"):
        new, old = (per_material(tables["rows"], arm, budget, "psnr") for arm in ("v8", "v4"))
        if new:
            out["tables v8 - v4"][budget] = paired_interval([new[m] - old[m] for m in new])
    return out


def by_pattern(arms: dict[str, list[dict]]) -> dict:
    """Pattern → budget → each arm's mean PSNR / ΔE over the 19 and `v8 − v4` per measurement."""
    out = {}
    for pattern in sorted({r["pattern"] for r in arms["v8"]}, key=[r["pattern"] for r in arms["v8"]].index):
        for budget in sorted({r["budget"] for r in arms["v8"]}, key=[r["budget"] for r in arms["v8"]].index):
            mine = {arm: [r for r in rows if r["pattern"] == pattern] for arm, rows in arms.items()}
            psnr = {arm: per_material(rows, arm, budget, "psnr") for arm, rows in mine.items()}
            delta_e = {arm: per_material(rows, arm, budget, "delta_e") for arm, rows in mine.items()}
            out.setdefault(pattern, {})[budget] = {
                **{arm: [float(np.mean(list(psnr[arm].values()))), float(np.mean(list(delta_e[arm].values())))]
                   for arm in ARMS},
                "v8 - v4": paired_interval([psnr["v8"][m] - psnr["v4"][m] for m in psnr["v8"]]),
            }
        # What the coverage weights add to `latent` with the `v8` runs (the CLI's default for a device's samples).
        plain, weighted = (per_material([r for r in arms["v8"] if r["pattern"] == pattern], "v8", budget, "psnr")
                           for budget in ("latent", "latent@coverage_k=32"))
        out[pattern]["coverage - latent, v8"] = paired_interval([weighted[m] - plain[m] for m in plain])
    return out


def markdown(summary: dict) -> str:
    interval = lambda d: f"{d['mean']:+.2f} [{d['low']:+.2f}, {d['high']:+.2f}]"  # noqa: E731
    lines = ["| arm, budget | PSNR / ΔE, 19 measurements | goal | ΔE > 6 |", "|---|---|---|---|"]
    for arm, budgets in summary["arms"].items():
        for budget, s in budgets.items():
            lost = ", ".join(f"{m} {d}" for m, d in s["hue_lost"].items()) or "none"
            goal = "met" if s["meets_goal"] else "not met"
            lines.append(f"| {arm}, {budget} | {s['psnr']:.2f} / {s['delta_e']:.2f} | {goal} | {lost} |")
    kinds = list(next(iter(summary["arms"].values()))["none"]["by_kind"])
    lines += ["", "| arm, budget | " + " | ".join(kinds) + " |", "|---|" + "---|" * len(kinds)]
    for arm, budgets in summary["arms"].items():
        for budget, s in budgets.items():
            cells = " | ".join(f"{p:.1f} / {d:.2f}" for p, d in s["by_kind"].values())
            lines.append(f"| {arm}, {budget} | {cells} |")
    lines += ["", "| `v8 − v4`, PSNR per material, 95 % interval | 19 measurements | 40 tables |", "|---|---|---|"]
    for budget, d in summary["v8 - v4"].items():
        table = summary["tables v8 - v4"].get(budget)
        lines.append(f"| {budget} | {interval(d)} | {interval(table) if table else '—'} |")
    if "patterns" in summary:
        lines += ["", "| pattern × 1,500, budget | v4 | v8 | `v8 − v4` |", "|---|---|---|---|"]
        for pattern, budgets in summary["patterns"].items():
            for budget, s in budgets.items():
                if budget == "coverage - latent, v8":
                    lines.append(f"| {pattern}, coverage − `latent` (`v8`) | | | {interval(s)} |")
                    continue
                arms = " | ".join(f"{s[arm][0]:.2f} / {s[arm][1]:.2f}" for arm in ARMS)
                lines.append(f"| {pattern}, {budget} | {arms} | {interval(s['v8 - v4'])} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    out = Path((argv or sys.argv[1:])[0])
    measured, tables = (json.loads((out / part / "compare.json").read_text()) for part in ("measured", "tables"))
    summary = summarise(measured, tables)
    if all((out / f"patterns-{arm}" / "compare.json").exists() for arm in ARMS):
        summary["patterns"] = by_pattern({arm: json.loads((out / f"patterns-{arm}" / "compare.json").read_text())["rows"]
                                          for arm in ARMS})
    save_json(out / "goals.json", summary)
    write_text(out / "goals.md", markdown(summary))
    print(markdown(summary))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
