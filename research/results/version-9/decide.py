"""The decision of research/results/version-9, by the rule fixed before its scores (README.md).

    python research/results/version-9/decide.py OUT

OUT is evaluate.sh's output. Version 9 replaces version 8 if, on the 40 held-out tables (OUT/tables, 4,000 random
bins), the per-table PSNR difference `v9 − v8` has its 95 % interval not wholly below 0 for the encoder (budget
``none``) and for ``latent``. Writes OUT/decision.json.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json

BUDGETS = ("none", "latent")


def differences(rows: list[dict], budget: str) -> dict[str, float]:
    """Table → `v9 − v8` PSNR under one budget."""
    psnr = {(r["model"], r["material"]): r["psnr"] for r in rows if r["budget"] == budget}
    return {m: psnr["v9", m] - psnr["v8", m] for (model, m) in sorted(psnr) if model == "v9"}


def main(argv=None) -> int:
    out = Path((argv or sys.argv[1:])[0])
    rows = json.loads((out / "tables" / "compare.json").read_text())["rows"]
    decision = {budget: paired_interval(list(differences(rows, budget).values())) for budget in BUDGETS}
    if any(decision[budget]["n"] != 40 for budget in BUDGETS):
        raise SystemExit(f"expected the 40 held-out tables, found {[decision[b]['n'] for b in BUDGETS]}")
    decision["rule"] = {budget: bool(decision[budget]["high"] > 0) for budget in BUDGETS}
    decision["ships"] = all(decision["rule"].values())
    save_json(out / "decision.json", decision)
    for budget in BUDGETS:
        v = decision[budget]
        print(f"{budget}: v9 − v8 {v['mean']:+.2f} dB [{v['low']:+.2f}, {v['high']:+.2f}] (n={v['n']})")
    print("rule:", decision["rule"], "→ version 9", "ships" if decision["ships"] else "does not ship")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
