"""The rule of research/results/look-ensemble (README.md), from run.sh's readings.

    python research/results/look-ensemble/decide.py OUT

Per material, the three looks averaged (twice) − version 11, in render PSNR (means over both draws); the rule of
research/studies/look_rule.py with the new families first and the tables second.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from look_rule import rule, table  # noqa: E402

JUDGED = ("families", "tables")


def main(out: Path) -> int:
    verdicts = {}
    for name in (*JUDGED, "measured"):
        candidate, base = out / name / "ensemble" / "rows.json", out / name / "v11" / "rows.json"
        if not (candidate.exists() and base.exists()):
            continue
        text, verdicts[name] = table(candidate, base)
        print(f"\n{name}: the three looks averaged − version 11, per material, 95 % interval\n\n{text}")
    if not set(JUDGED) <= set(verdicts):
        print("\nthe families' or the tables' readings are missing: no decision")
        return 1
    passes, reasons = rule(verdicts["families"], verdicts["tables"])
    print(f"\n{reasons}\nrule: " + ("PASSES, the three looks averaged earn a place in the shipped model" if passes
                                   else "fails, version 11 stays"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1])))
