"""The rule of research/results/second-look (README.md), from run.sh's readings.

    python research/results/second-look/decide.py OUT

Per material, second − first look in render PSNR (and ΔE), the second look the mean of the three runs, both draws;
per pattern and the five devices' mean; 95 % t-intervals over the materials. (a) families' five-device mean above
0, (b) tables' not wholly below 0, (c) random bins not wholly below 0 on either set.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

DEVICES = ("uniform", "in-plane", "gonioreflectometer", "image-based", "specular")


def differences(rows: list[dict], key: str) -> dict[str, dict[str, float]]:
    """``{pattern: {material: second − first}}`` (each the mean over draws, the second look's over its runs), and
    ``"devices"``: the five devices' mean."""
    out = {}
    for pattern in ("merl-bins", *DEVICES):
        out[pattern] = {}
        for material in sorted({r["material"] for r in rows}):
            here = [r for r in rows if r["material"] == material and r["pattern"] == pattern]
            first = np.mean([r[key] for r in here if r["look"] == "first"])
            second = np.mean([r[key] for r in here if r["look"] != "first"])
            out[pattern][material] = float(second - first)
    out["devices"] = {m: float(np.mean([out[p][m] for p in DEVICES])) for m in out["merl-bins"]}
    return out


def cell(values: dict) -> str:
    i = paired_interval(list(values.values()))
    return f"{i['mean']:+.2f} [{i['low']:+.2f}, {i['high']:+.2f}]"


def main(out: Path) -> int:
    verdicts = {}
    for name in ("families", "tables", "measured"):
        path = out / name / "rows.json"
        if not path.exists():
            continue
        rows = json.loads(path.read_text())
        psnr, delta_e = differences(rows, "psnr"), differences(rows, "delta_e")
        print(f"\n{name}: second − first look, per material, 95 % interval ({len(psnr['devices'])} materials)\n")
        print("| pattern | PSNR (dB) | ΔE |\n|---|---|---|")
        for pattern in psnr:
            print(f"| {pattern} | {cell(psnr[pattern])} | {cell(delta_e[pattern])} |")
        verdicts[name] = {pattern: paired_interval(list(v.values())) for pattern, v in psnr.items()}
    if not {"families", "tables"} <= set(verdicts):
        print("\nthe families' or the tables' readings are missing: no decision")
        return 1
    a = verdicts["families"]["devices"]["low"] > 0
    b = verdicts["tables"]["devices"]["high"] >= 0
    c = all(verdicts[name]["merl-bins"]["high"] >= 0 for name in ("families", "tables"))
    print(f"\n(a) families' devices above 0: {a}; (b) tables' devices not wholly below 0: {b}; "
          f"(c) random bins not wholly below 0 on either: {c}")
    print("rule: " + ("PASSES, the second look earns its place in the shipped model" if a and b and c
                      else "fails, the second look stays a study"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1])))
