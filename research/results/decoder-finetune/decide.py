"""decoder-finetune's rule (README.md): each fold's fine-tuned run against the same run before (`ft` − `base`,
paired per material).

    python research/results/decoder-finetune/decide.py OUT [--arm ft]   (OUT: run.sh's fF/ and tables/ readings;
                                                                      --arm refit: the amendment's runs;
                                                                      --arm joint --encoder-rule: the second's;
                                                                      --arm anchor, --arm augment: the third's
                                                                      and fourth's, with --encoder-rule)
    python research/results/decoder-finetune/decide.py OUT OUT2 ... --to DIR [--arm ...]
        (readings of fits from other seeds against the same base, on the same draw: each material's figure the
        mean over them; writes DIR/decision.json)

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
    parser.add_argument("out", type=Path, nargs="+", help="run.sh's readings: one, or one a fit seed")
    parser.add_argument("--to", type=Path, help="where decision.json goes (default: the first OUT)")
    parser.add_argument("--arm", default="ft", help="the candidate's label in the readings")
    parser.add_argument("--encoder-rule", action="store_true",
                        help="the second amendment's rule: also (d) and (e), the encoder not wholly below 0")
    args = parser.parse_args(argv)
    arm = args.arm
    measured = rows_of([path for out in args.out for path in sorted(out.glob("f*/compare.json"))])
    tables = rows_of([out / "tables" / "compare.json" for out in args.out])
    fig = {(a, budget): figures(measured, a, budget) for a in ("base", arm) for budget in BUDGETS}
    if any(len(fig[key]) != 19 for key in fig):
        raise SystemExit(f"expected 19 measurements a reading, got { {k: len(v) for k, v in fig.items()} }")
    change = {budget: difference(fig[arm, budget], fig["base", budget]) for budget in BUDGETS}
    folds = [difference(fig[arm, "latent"], fig["base", "latent"], names)["mean"] for names in FOLDS["folds"]]
    table = {budget: difference(figures(tables, arm, budget), figures(tables, "base", budget))
             for budget in ("none", "latent")}
    tests = {
        "a: latent per measurement above 0": change["latent"]["low"] > 0,
        "b: each fold's mean above 0": all(f > 0 for f in folds),
        "c: tables' latent not wholly below 0": table["latent"]["high"] >= 0,
    }
    if args.encoder_rule:
        tests["d: encoder per measurement not wholly below 0"] = change["none"]["high"] >= 0
        tests["e: tables' encoder not wholly below 0"] = table["none"]["high"] >= 0
    arms = ("base", arm)
    reported = {f"{a} {budget}": mean_of(fig[a, budget], sorted(fig[a, budget])) for a in arms for budget in BUDGETS}
    reported |= {f"{a} {budget} by kind": {kind: mean_of(fig[a, budget], names) for kind, names in FOLDS["kinds"].items()}
                 for a in arms for budget in BUDGETS}
    reported |= {f"tables {a} {budget}": mean_of(figures(tables, a, budget), sorted(figures(tables, a, budget)))
                 for a in arms for budget in ("none", "latent")}
    reported["ΔE > 6"] = {f"{a} {budget}": {m: round(v[1], 2) for m, v in fig[a, budget].items() if v[1] > 6}
                          for a in arms for budget in BUDGETS}
    decision = {"passes": all(tests.values()), "tests": tests, "change": change, "fold means": folds,
                "tables": table, "reported": reported}
    to = args.to or args.out[0]
    to.mkdir(parents=True, exist_ok=True)
    (to / "decision.json").write_text(json.dumps(decision, indent=1, ensure_ascii=False) + "\n")
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
