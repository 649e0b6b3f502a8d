"""latent-size's rule (README.md): a candidate arm (one run a fold) against `mf` (the mean of its fold's three runs).

    python research/results/latent-size/decide.py OUT [--arm mf128]
        [--mf research/results/real-in-data/out]   (its measured/, seeds/*/ and tables/ readings)

The candidate is `mf128` (latent-size) by default; research/results/decoder-width judges `mfw512` by the same rule.
Each arm's figures per material are real-in-data's seeds.py's (the mean over the arm's runs).

OUT holds score_runs.sh's `ARM-fF-s0/compare.json` and score_tables.sh's `tables/compare.json`. Writes
OUT/decision.json and prints the rule's tests and what is reported beside them.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

STUDIES = Path(__file__).resolve().parents[2] / "studies"
FOLDS = json.loads((STUDIES / "measured_folds" / "folds.json").read_text())
REAL_IN_DATA = Path(__file__).resolve().parent.parent / "real-in-data"

sys.path.insert(0, str(REAL_IN_DATA))
from seeds import per_material as figures  # noqa: E402  (material → (PSNR, ΔE, runs), the mean over an arm's runs)


def rows_of(paths) -> list[dict]:
    return [row for path in paths for row in json.loads(Path(path).read_text())["rows"]]


def difference(new: dict, old: dict, names=None) -> dict:
    names = sorted((new.keys() & old.keys()) if names is None else names)
    return paired_interval([new[m][0] - old[m][0] for m in names]) | {"materials": len(names)}


def mean_of(fig: dict, names) -> list[float]:
    return [float(np.mean([fig[m][i] for m in names])) for i in (0, 1)]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path)
    parser.add_argument("--arm", default="mf128", help="the candidate arm's name (its runs' labels)")
    parser.add_argument("--mf", type=Path, default=REAL_IN_DATA / "out")
    args = parser.parse_args(argv)
    arm = args.arm
    measured = rows_of([args.mf / "measured" / "compare.json", *sorted(args.mf.glob("seeds/*/compare.json")),
                        *sorted(args.out.glob(f"{arm}-f*/compare.json"))])
    tables = rows_of([args.mf / "tables" / "compare.json", args.out / "tables" / "compare.json"])
    arms = ("mf", arm)
    fig = {(a, budget): figures(measured, a, budget) for a in arms for budget in ("none", "latent", "full")}
    if len(fig[arm, "latent"]) != 19:
        raise SystemExit(f"{arm} read {len(fig[arm, 'latent'])} measurements with latent; expected 19")
    latent = difference(fig[arm, "latent"], fig["mf", "latent"])
    folds = [difference(fig[arm, "latent"], fig["mf", "latent"], names)["mean"] for names in FOLDS["folds"]]
    encoder = difference(fig[arm, "none"], fig["mf", "none"])
    table = difference(figures(tables, arm, "latent"), figures(tables, "mf", "latent"))
    tests = {
        "a: latent per measurement above 0": latent["low"] > 0,
        "b: each fold's mean above 0": all(f > 0 for f in folds),
        "c: encoder not wholly below 0": encoder["high"] >= 0,
        "d: tables' latent not wholly below 0": table["high"] >= 0,
    }
    reported = {
        f"{a} {budget}": mean_of(fig[a, budget], sorted(fig[a, budget])) for a in arms for budget in ("none", "latent", "full")
    }
    reported |= {f"{a} {budget} by kind": {kind: mean_of(fig[a, budget], names) for kind, names in FOLDS["kinds"].items()}
                 for a in arms for budget in ("none", "latent", "full")}
    reported[f"full, {arm} − mf"] = difference(fig[arm, "full"], fig["mf", "full"])
    reported[f"tables' encoder, {arm} − mf"] = difference(figures(tables, arm, "none"), figures(tables, "mf", "none"))
    reported["ΔE > 6"] = {f"{a} {budget}": {m: round(v[1], 2) for m, v in fig[a, budget].items() if v[1] > 6}
                          for a in arms for budget in ("none", "latent", "full")}
    decision = {"passes": all(tests.values()), "tests": tests, "latent": latent, "fold means": folds,
                "encoder": encoder, "tables' latent": table, "reported": reported}
    (args.out / "decision.json").write_text(json.dumps(decision, indent=1, ensure_ascii=False) + "\n")
    for name, passed in tests.items():
        print(f"{'pass' if passed else 'FAIL'}  {name}")
    print(f"latent {latent['mean']:+.2f} [{latent['low']:+.2f}, {latent['high']:+.2f}]; folds "
          + ", ".join(f"{f:+.2f}" for f in folds) + f"; encoder {encoder['mean']:+.2f} [{encoder['low']:+.2f}, "
          f"{encoder['high']:+.2f}]; tables {table['mean']:+.2f} [{table['low']:+.2f}, {table['high']:+.2f}]")
    for name, value in reported.items():
        print(name, value)
    print("the rule:", "passes" if decision["passes"] else "fails")


if __name__ == "__main__":
    main()
