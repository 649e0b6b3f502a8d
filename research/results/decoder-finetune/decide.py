"""decoder-finetune's rule (README.md): each fold's fine-tuned run against the same run before (`ft` − `base`,
paired per material).

    python research/results/decoder-finetune/decide.py OUT   (OUT: run.sh's fF/ and tables/ readings)

Writes OUT/decision.json and prints the rule's tests and what is reported beside them.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "latent-size"))
from decide import FOLDS, difference, figures, mean_of, rows_of  # noqa: E402

BUDGETS = ("none", "latent", "full")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path)
    args = parser.parse_args(argv)
    measured = rows_of(sorted(args.out.glob("f*/compare.json")))
    tables = rows_of([args.out / "tables" / "compare.json"])
    fig = {(arm, budget): figures(measured, arm, budget) for arm in ("base", "ft") for budget in BUDGETS}
    if any(len(fig[key]) != 19 for key in fig):
        raise SystemExit(f"expected 19 measurements a reading, got { {k: len(v) for k, v in fig.items()} }")
    change = {budget: difference(fig["ft", budget], fig["base", budget]) for budget in BUDGETS}
    folds = [difference(fig["ft", "latent"], fig["base", "latent"], names)["mean"] for names in FOLDS["folds"]]
    table = {budget: difference(figures(tables, "ft", budget), figures(tables, "base", budget))
             for budget in ("none", "latent")}
    tests = {
        "a: latent per measurement above 0": change["latent"]["low"] > 0,
        "b: each fold's mean above 0": all(f > 0 for f in folds),
        "c: tables' latent not wholly below 0": table["latent"]["high"] >= 0,
    }
    reported = {f"{arm} {budget}": mean_of(fig[arm, budget], sorted(fig[arm, budget]))
                for arm in ("base", "ft") for budget in BUDGETS}
    reported |= {f"{arm} {budget} by kind": {kind: mean_of(fig[arm, budget], names)
                                             for kind, names in FOLDS["kinds"].items()}
                 for arm in ("base", "ft") for budget in BUDGETS}
    reported |= {f"tables {arm} {budget}": mean_of(figures(tables, arm, budget), sorted(figures(tables, arm, budget)))
                 for arm in ("base", "ft") for budget in ("none", "latent")}
    reported["ΔE > 6"] = {f"{arm} {budget}": {m: round(v[1], 2) for m, v in fig[arm, budget].items() if v[1] > 6}
                          for arm in ("base", "ft") for budget in BUDGETS}
    decision = {"passes": all(tests.values()), "tests": tests, "change": change, "fold means": folds,
                "tables": table, "reported": reported}
    (args.out / "decision.json").write_text(json.dumps(decision, indent=1, ensure_ascii=False) + "\n")
    for name, passed in tests.items():
        print(f"{'pass' if passed else 'FAIL'}  {name}")
    for budget, c in change.items():
        print(f"{budget}: {c['mean']:+.2f} [{c['low']:+.2f}, {c['high']:+.2f}]")
    print("latent by fold " + ", ".join(f"{f:+.2f}" for f in folds))
    for budget, c in table.items():
        print(f"tables {budget}: {c['mean']:+.2f} [{c['low']:+.2f}, {c['high']:+.2f}]")
    for name, value in reported.items():
        print(name, value)
    print("the rule:", "passes" if decision["passes"] else "fails")


if __name__ == "__main__":
    main()
