"""The rule of research/results/repeated-look (README.md), from run.sh's readings.

    python research/results/repeated-look/decide.py OUT

Per material, 2 looks − 1 look in render PSNR (means over both draws), per pattern and the five devices' mean; 95 %
t-intervals over the materials. (a) The new families' five-device mean above 0; (b) the unseen tables' not wholly
below 0; (c) random bins not wholly below 0 on either set; (d) no device wholly below 0 on either set.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from repeated_look import per_material  # noqa: E402

from frenbrdf.evaluation.statistics import paired_interval  # noqa: E402

DEVICES = ("uniform", "in-plane", "gonioreflectometer", "image-based", "specular")
JUDGED = ("families", "tables")


def differences(rows: list[dict], key: str) -> dict[str, list[float]]:
    """``{pattern: [2 looks − 1, per material]}``, and ``"devices"``: the five devices' mean per material."""
    out = {}
    for pattern in ("merl-bins", *DEVICES):
        looks = per_material([r for r in rows if r["pattern"] == pattern], key)
        out[pattern] = [looks[2][m] - looks[1][m] for m in looks[1]]
    out["devices"] = list(np.mean([out[p] for p in DEVICES], axis=0))
    return out


def cell(values: list[float]) -> str:
    i = paired_interval(values)
    return f"{i['mean']:+.2f} [{i['low']:+.2f}, {i['high']:+.2f}]"


def main(out: Path) -> int:
    verdicts = {}
    for name in (*JUDGED, "tables-seen", "measured"):
        path = out / name / "rows.json"
        if not path.exists():
            continue
        rows = json.loads(path.read_text())
        psnr, delta_e = differences(rows, "psnr"), differences(rows, "delta_e")
        print(f"\n{name}: 2 looks − 1, per material, 95 % interval ({len(psnr['devices'])} materials)\n")
        print("| pattern | PSNR (dB) | ΔE |\n|---|---|---|")
        for pattern in psnr:
            print(f"| {pattern} | {cell(psnr[pattern])} | {cell(delta_e[pattern])} |")
        verdicts[name] = {pattern: paired_interval(values) for pattern, values in psnr.items()}
    if not set(JUDGED) <= set(verdicts):
        print("\nthe families' or the unseen tables' readings are missing: no decision")
        return 1
    a = verdicts["families"]["devices"]["low"] > 0
    b = verdicts["tables"]["devices"]["high"] >= 0
    c = all(verdicts[name]["merl-bins"]["high"] >= 0 for name in JUDGED)
    d = all(verdicts[name][pattern]["high"] >= 0 for name in JUDGED for pattern in DEVICES)
    print(f"\n(a) families' devices above 0: {a}; (b) tables' devices not wholly below 0: {b}; "
          f"(c) random bins not wholly below 0 on either: {c}; (d) no device wholly below 0 on either: {d}")
    print("rule: " + ("PASSES, the model takes two looks" if a and b and c and d else "fails, one look stays"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1])))
