"""The full-tie study's rule (README.md) from run.sh's readings in OUT.

    python research/results/full-tie/decide.py OUT
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from paired_arms import interval  # noqa: E402

BASE, TIED = "full", "full@tie=0.1"


def paired(compare: Path) -> dict:
    """Tied − untied per material: PSNR and ΔE, each a mean and interval."""
    rows = json.loads(compare.read_text())["rows"]
    by = {(row["material"], row["budget"]): row for row in rows}
    materials = sorted({row["material"] for row in rows})
    result = {}
    for key in ("psnr", "delta_e"):
        result[key] = interval([by[m, TIED][key] - by[m, BASE][key] for m in materials])
    result["materials"] = len(materials)
    result["mean"] = {budget: float(sum(by[m, budget]["psnr"] for m in materials) / len(materials))
                      for budget in (BASE, TIED)}
    return result


def main() -> None:
    out = Path(sys.argv[1])
    decision: dict = {}
    harmless = True
    for name in ("measured", "tables"):
        reading = paired(out / name / "compare.json")
        decision[name] = reading
        passes = reading["psnr"][1] > -0.3 and reading["delta_e"][0] < 0.05
        harmless &= passes
        print(f"{name} ({reading['materials']}): PSNR {reading['mean'][BASE]:.2f} → {reading['mean'][TIED]:.2f}, "
              f"tied − full {reading['psnr'][0]:+.2f} dB [{reading['psnr'][1]:+.2f}, {reading['psnr'][2]:+.2f}], "
              f"ΔE {reading['delta_e'][0]:+.3f} [{reading['delta_e'][1]:+.3f}, {reading['delta_e'][2]:+.3f}]: "
              f"(b) {'passes' if passes else 'fails'}")
    summary = json.loads((out / "seam.json").read_text())["summary"]
    seam_passes = (summary[TIED]["median"] <= summary[BASE]["median"] / 2
                   and summary[TIED]["p90"] <= summary[BASE]["p90"] * 2 / 3)
    print(f"seam step median / p90: full {summary[BASE]['median']:.4f} / {summary[BASE]['p90']:.4f}, tied "
          f"{summary[TIED]['median']:.4f} / {summary[TIED]['p90']:.4f}: (a) {'passes' if seam_passes else 'fails'}")
    timing = (out / "timing.txt").read_text()
    ratio = float(re.search(r"ratio ([\d.]+)", timing).group(1))
    tied_seconds = float(re.search(rf"{re.escape(TIED)}: mean ([\d.]+) s", timing).group(1))
    time_passes = ratio <= 1.08 and tied_seconds <= 2.0
    print(f"time: {tied_seconds:.3f} s tied, {ratio:.3f}× full: (c) {'passes' if time_passes else 'fails'}")
    decision |= {"seam": summary, "time_ratio": ratio, "tied_seconds": tied_seconds,
                 "ships": bool(harmless and seam_passes and time_passes)}
    print("the tie goes into full:", decision["ships"])
    (out / "decision.json").write_text(json.dumps(decision, indent=2) + "\n")


if __name__ == "__main__":
    main()
