"""The decision of research/results/version-9, by the rule fixed before its scores (README.md).

    python research/results/version-9/decide.py OUT [--labels v9 v10]

OUT is evaluate.sh's output (``--labels``: its LABELS, the baseline first; research/results/version-10 reads
version 9 against its candidate by the same rule). Version 9 replaces version 8 if, on the 40 held-out tables (OUT/tables, 4,000 random
bins), the per-table PSNR difference `v9 − v8` has its 95 % interval not wholly below 0 for the encoder (budget
``none``) and for ``latent``. Writes OUT/decision.json.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json

BUDGETS = ("none", "latent")


def differences(rows: list[dict], budget: str, old: str = "v8", new: str = "v9") -> dict[str, float]:
    """Table → `new − old` PSNR under one budget."""
    psnr = {(r["model"], r["material"]): r["psnr"] for r in rows if r["budget"] == budget}
    return {m: psnr[new, m] - psnr[old, m] for (model, m) in sorted(psnr) if model == new}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--labels", nargs=2, default=["v8", "v9"], metavar=("OLD", "NEW"))
    args = parser.parse_args(argv)
    out, (old, new) = args.out, args.labels
    rows = json.loads((out / "tables" / "compare.json").read_text())["rows"]
    decision = {budget: paired_interval(list(differences(rows, budget, old, new).values())) for budget in BUDGETS}
    if any(decision[budget]["n"] != 40 for budget in BUDGETS):
        raise SystemExit(f"expected the 40 held-out tables, found {[decision[b]['n'] for b in BUDGETS]}")
    decision["rule"] = {budget: bool(decision[budget]["high"] > 0) for budget in BUDGETS}
    decision["ships"] = all(decision["rule"].values())
    save_json(out / "decision.json", decision)
    for budget in BUDGETS:
        v = decision[budget]
        print(f"{budget}: {new} − {old} {v['mean']:+.2f} dB [{v['low']:+.2f}, {v['high']:+.2f}] (n={v['n']})")
    print("rule:", decision["rule"], "→", new, "ships" if decision["ships"] else "does not ship")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
