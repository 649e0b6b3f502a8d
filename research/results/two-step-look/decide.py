"""The rule of research/results/two-step-look (README.md), from run.sh's readings.

    python research/results/two-step-look/decide.py OUT

Per material, the three runs' mean − version 11 in render PSNR (and ΔE), two looks each, means over both draws;
per pattern and the five devices' mean; 95 % t-intervals over the materials. (a) The new families' five-device mean
above 0; (b) the tables' not wholly below 0; (c) random bins not wholly below 0 on either set; (d) no device wholly
below 0 on either set.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

DEVICES = ("uniform", "in-plane", "gonioreflectometer", "image-based", "specular")
JUDGED = ("families", "tables")
RUNS = ("s1", "s2", "s3")


def by_material(rows: list[dict], pattern: str, key: str) -> dict[str, float]:
    """``{material: key}`` through ``pattern``, each the mean over the draws."""
    return {m: float(np.mean([r[key] for r in rows if r["material"] == m and r["pattern"] == pattern]))
            for m in sorted({r["material"] for r in rows})}


def differences(folder: Path, key: str) -> dict[str, list[float]]:
    """``{pattern: [runs' mean − version 11, per material]}`` and ``"devices"``: the five devices' mean."""
    rows = {label: json.loads((folder / label / "rows.json").read_text()) for label in ("v11", *RUNS)}
    out = {}
    for pattern in ("merl-bins", *DEVICES):
        base = by_material(rows["v11"], pattern, key)
        runs = [by_material(rows[run], pattern, key) for run in RUNS]
        out[pattern] = [float(np.mean([run[m] for run in runs]) - base[m]) for m in base]
    out["devices"] = list(np.mean([out[p] for p in DEVICES], axis=0))
    return out


def cell(values: list[float]) -> str:
    i = paired_interval(values)
    return f"{i['mean']:+.2f} [{i['low']:+.2f}, {i['high']:+.2f}]"


def main(out: Path) -> int:
    verdicts = {}
    for name in (*JUDGED, "measured"):
        if not all((out / name / label / "rows.json").exists() for label in ("v11", *RUNS)):
            continue
        psnr, delta_e = differences(out / name, "psnr"), differences(out / name, "delta_e")
        print(f"\n{name}: the two-step runs' mean − version 11, two looks, per material, 95 % interval "
              f"({len(psnr['devices'])} materials)\n")
        print("| pattern | PSNR (dB) | ΔE |\n|---|---|---|")
        for pattern in psnr:
            print(f"| {pattern} | {cell(psnr[pattern])} | {cell(delta_e[pattern])} |")
        verdicts[name] = {pattern: paired_interval(values) for pattern, values in psnr.items()}
    if not set(JUDGED) <= set(verdicts):
        print("\nthe families' or the tables' readings are missing: no decision")
        return 1
    a = verdicts["families"]["devices"]["low"] > 0
    b = verdicts["tables"]["devices"]["high"] >= 0
    c = all(verdicts[name]["merl-bins"]["high"] >= 0 for name in JUDGED)
    d = all(verdicts[name][pattern]["high"] >= 0 for name in JUDGED for pattern in DEVICES)
    print(f"\n(a) families' devices above 0: {a}; (b) tables' devices not wholly below 0: {b}; "
          f"(c) random bins not wholly below 0 on either: {c}; (d) no device wholly below 0 on either: {d}")
    print("rule: " + ("PASSES, the two-step look ships" if a and b and c and d else "fails, version 11 stays"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1])))
