"""The decision of research/results/real-in-data, by the rule fixed before its runs (README.md).

    python research/results/real-in-data/decide.py OUT

OUT is evaluate.sh's output (the `mf` rows). Its rows are joined with folds-v8's `v8` rows (the same draws) into
OUT/with-v8/{measured,tables}/compare.json, so that `folds-v8/summarise.py OUT/with-v8 --arms v8 mf` prints the
goals' table (and the table per pattern from evaluate.sh's `patterns-mf`). The rule, encoder PSNR (budget
``none``), each arm's figure per material the mean over its runs: (a) `mf − v8` over the 19 measurements has its
95 % interval above 0, (b) each fold's mean of that difference over its own measurements is above 0, (c) on the 40
tables the interval is not wholly below 0. Writes OUT/decision.json.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json

HERE = Path(__file__).resolve().parent
FOLDS_V8 = HERE.parent / "folds-v8"
FOLDS = json.loads((HERE.parents[1] / "studies" / "measured_folds" / "folds.json").read_text())["folds"]


def per_material(rows: list[dict], arm: str) -> dict[str, float]:
    """Material → the arm's encoder PSNR, the mean over its runs."""
    mine = [r for r in rows if r["model"].split("/")[0] == arm and r["budget"] == "none"]
    return {m: float(np.mean([r["psnr"] for r in mine if r["material"] == m])) for m in {r["material"] for r in mine}}


def differences(rows: list[dict]) -> dict[str, float]:
    new, old = per_material(rows, "mf"), per_material(rows, "v8")
    return {m: new[m] - old[m] for m in sorted(new.keys() & old.keys())}


def joined(name: str, out: Path) -> list[dict]:
    """folds-v8's `v8` rows and this study's rows of one report, written to OUT/with-v8/NAME/compare.json."""
    theirs = json.loads((FOLDS_V8 / name / "compare.json").read_text())
    ours = json.loads((out / name / "compare.json").read_text())
    rows = [r for r in theirs["rows"] if r["model"].startswith("v8/")] + ours["rows"]
    save_json(out / "with-v8" / name / "compare.json", {**ours, "rows": rows})
    return rows


def main(argv=None) -> int:
    out = Path((argv or sys.argv[1:])[0])
    measured = differences(joined("measured", out))
    tables = differences(joined("tables", out))
    if (out / "patterns-mf").exists():  # issue 47's table, for summarise.py: both arms' readings side by side
        for arm, source in (("v8", FOLDS_V8), ("mf", out)):
            save_json(out / "with-v8" / f"patterns-{arm}" / "compare.json",
                      json.loads((source / f"patterns-{arm}" / "compare.json").read_text()))
    if len(measured) != sum(map(len, FOLDS)):
        raise SystemExit(f"expected the {sum(map(len, FOLDS))} measurements, found {len(measured)}")
    folds = [float(np.mean([measured[m] for m in fold])) for fold in FOLDS]
    decision = {"measurements": paired_interval(list(measured.values())), "folds": folds,
                "tables": paired_interval(list(tables.values())), "per_measurement": measured}
    decision["rule"] = {"a": bool(decision["measurements"]["low"] > 0), "b": bool(min(folds) > 0),
                        "c": bool(decision["tables"]["high"] > 0)}
    decision["joins"] = all(decision["rule"].values())
    save_json(out / "decision.json", decision)
    for key in ("measurements", "tables"):
        v = decision[key]
        print(f"{key}: mf − v8 encoder {v['mean']:+.2f} dB [{v['low']:+.2f}, {v['high']:+.2f}] (n={v['n']})")
    print("each fold's mean:", ", ".join(f"{f:+.2f}" for f in folds))
    print("rule:", decision["rule"], "→ the measurements and families",
          "join the next retrain's data" if decision["joins"] else "do not join")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
