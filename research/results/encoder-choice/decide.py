"""The rule of research/results/encoder-choice (README.md), from run.sh's readings.

    python research/results/encoder-choice/decide.py OUT

Per material, coverage-weighted choice − plain `best-fit` in render PSNR (and ΔE), over both draws, per pattern and
over the five; 95 % t-intervals over the materials; (a) families' five-pattern mean above 0, (b) tables' not wholly
below 0, (c) no pattern's interval wholly below 0 on either set.
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval


def differences(rows: list[dict], key: str) -> dict[str, dict[str, float]]:
    """``{pattern: {material: mean over draws of (coverage pick − plain pick)}}``, and ``"all"`` over the patterns."""
    groups = defaultdict(list)
    for row in rows:
        if row["encoder"] != "mean":
            groups[row["material"], row["pattern"], row["draw"]].append(row)
    per = defaultdict(lambda: defaultdict(list))
    for (material, pattern, _), members in groups.items():
        plain = min(members, key=lambda r: r["loss"])
        coverage = min(members, key=lambda r: r["coverage_loss"])
        per[pattern][material].append(coverage[key] - plain[key])
    out = {pattern: {m: float(np.mean(d)) for m, d in materials.items()} for pattern, materials in per.items()}
    materials = sorted(next(iter(out.values())))
    out["all"] = {m: float(np.mean([out[p][m] for p in per])) for m in materials}
    return out


def line(name: str, psnr: dict, delta_e: dict) -> str:
    i, e = paired_interval(list(psnr.values())), paired_interval(list(delta_e.values()))
    return (f"| {name} | {i['mean']:+.2f} [{i['low']:+.2f}, {i['high']:+.2f}] | {e['mean']:+.2f} [{e['low']:+.2f}, "
            f"{e['high']:+.2f}] | {i['n']} |")


def main(out: Path) -> int:
    verdicts, report = {}, []
    for name in ("families", "tables", "measured"):
        path = out / name / "rows.json"
        if not path.exists():
            continue
        rows = json.loads(path.read_text())
        psnr, delta_e = differences(rows, "psnr"), differences(rows, "delta_e")
        report += [f"\n{name}: coverage-weighted choice − plain `best-fit`, per material, 95 % interval\n",
                   "| pattern | PSNR (dB) | ΔE | materials |", "|---|---|---|---|"]
        report += [line(pattern, psnr[pattern], delta_e[pattern]) for pattern in psnr]
        verdicts[name] = {pattern: paired_interval(list(values.values())) for pattern, values in psnr.items()}
    print("\n".join(report))
    if not {"families", "tables"} <= set(verdicts):
        print("\nthe families' or the tables' readings are missing: no decision")
        return 1
    a = verdicts["families"]["all"]["low"] > 0
    b = verdicts["tables"]["all"]["high"] >= 0
    c = all(v["high"] >= 0 for name in ("families", "tables") for p, v in verdicts[name].items() if p != "all")
    print(f"\n(a) families above 0: {a}; (b) tables not wholly below 0: {b}; (c) no pattern wholly below 0: {c}")
    print("rule: " + ("PASSES, the coverage-weighted choice is adopted" if a and b and c else "fails, best-fit stays"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1])))
