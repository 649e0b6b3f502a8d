"""The encoder studies' rule, shared: per material, a candidate's reading minus a base's through each pattern, the
five devices' mean, 95 % intervals, and the four conditions (look-choice; the rules of second-look, repeated-look and
two-step-look were written out in each study's decide.py before this was shared)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

DEVICES = ("uniform", "in-plane", "gonioreflectometer", "image-based", "specular")
PATTERNS = ("merl-bins", *DEVICES)


def by_material(rows: list[dict], pattern: str, key: str) -> dict[str, float]:
    """``{material: key}`` through ``pattern``, each the mean over the draws."""
    return {m: float(np.mean([r[key] for r in rows if r["material"] == m and r["pattern"] == pattern]))
            for m in sorted({r["material"] for r in rows})}


def differences(candidate: Path, base: Path, key: str) -> dict[str, list[float]]:
    """``{pattern: [candidate − base, per material]}`` from two ``rows.json``, and ``"devices"``: the five devices'
    mean per material."""
    rows = [json.loads(path.read_text()) for path in (candidate, base)]
    out = {}
    for pattern in PATTERNS:
        new, old = (by_material(r, pattern, key) for r in rows)
        out[pattern] = [new[m] - old[m] for m in old]
    out["devices"] = list(np.mean([out[p] for p in DEVICES], axis=0))
    return out


def cell(values: list[float]) -> str:
    i = paired_interval(values)
    return f"{i['mean']:+.2f} [{i['low']:+.2f}, {i['high']:+.2f}]"


def table(candidate: Path, base: Path) -> tuple[str, dict[str, dict]]:
    """A Markdown table of the differences in PSNR and ΔE, and the PSNR intervals by pattern."""
    psnr, delta_e = differences(candidate, base, "psnr"), differences(candidate, base, "delta_e")
    lines = ["| pattern | PSNR (dB) | ΔE |", "|---|---|---|"]
    lines += [f"| {pattern} | {cell(psnr[pattern])} | {cell(delta_e[pattern])} |" for pattern in psnr]
    return "\n".join(lines), {pattern: paired_interval(values) for pattern, values in psnr.items()}


def rule(first: dict[str, dict], second: dict[str, dict]) -> tuple[bool, str]:
    """(a) the first set's five-device mean above 0; (b) the second's not wholly below 0; (c) random bins not wholly
    below 0 on either; (d) no device wholly below 0 on either. Whether all hold, and a line saying each."""
    a = first["devices"]["low"] > 0
    b = second["devices"]["high"] >= 0
    c = all(v["merl-bins"]["high"] >= 0 for v in (first, second))
    d = all(v[pattern]["high"] >= 0 for v in (first, second) for pattern in DEVICES)
    return a and b and c and d, (f"(a) first set's devices above 0: {a}; (b) second set's devices not wholly below "
                                 f"0: {b}; (c) random bins not wholly below 0 on either: {c}; (d) no device wholly "
                                 f"below 0 on either: {d}")


def decide(out: Path, candidate: str, base: str, compared: str, verdict: str) -> int:
    """A study's decision from ``OUT/{families,tables,measured}/{candidate,base}/rows.json``: each set's table
    (``compared`` names the difference), then the rule with the families first and the tables second (the
    measurements are reported only); ``verdict`` is printed where it passes."""
    judged = ("families", "tables")
    verdicts = {}
    for name in (*judged, "measured"):
        new, old = out / name / candidate / "rows.json", out / name / base / "rows.json"
        if not (new.exists() and old.exists()):
            continue
        text, verdicts[name] = table(new, old)
        print(f"\n{name}: {compared}, per material, 95 % interval\n\n{text}")
    if not set(judged) <= set(verdicts):
        print("\nthe families' or the tables' readings are missing: no decision")
        return 1
    passes, reasons = rule(verdicts["families"], verdicts["tables"])
    print(f"\n{reasons}\nrule: " + (verdict if passes else "fails, version 11 stays"))
    return 0
