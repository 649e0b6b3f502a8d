"""latent-size's rule (README.md): `mf128` (one run a fold) against `mf` (the mean of its fold's three runs).

    python research/results/latent-size/decide.py OUT
        [--mf research/results/real-in-data/out]   (its measured/, seeds/*/ and tables/ readings)

Each arm's figures per material are real-in-data's seeds.py's (the mean over the arm's runs).

OUT holds score_runs.sh's `mf128-fF-s0/compare.json` and score_tables.sh's `tables/compare.json`. Writes
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
    parser.add_argument("--mf", type=Path, default=REAL_IN_DATA / "out")
    args = parser.parse_args(argv)
    measured = rows_of([args.mf / "measured" / "compare.json", *sorted(args.mf.glob("seeds/*/compare.json")),
                        *sorted(args.out.glob("mf128-f*/compare.json"))])
    tables = rows_of([args.mf / "tables" / "compare.json", args.out / "tables" / "compare.json"])
    fig = {(arm, budget): figures(measured, arm, budget) for arm in ("mf", "mf128") for budget in ("none", "latent", "full")}
    if len(fig["mf128", "latent"]) != 19:
        raise SystemExit(f"mf128 read {len(fig['mf128', 'latent'])} measurements with latent; expected 19")
    latent = difference(fig["mf128", "latent"], fig["mf", "latent"])
    folds = [difference(fig["mf128", "latent"], fig["mf", "latent"], names)["mean"] for names in FOLDS["folds"]]
    encoder = difference(fig["mf128", "none"], fig["mf", "none"])
    table = difference(figures(tables, "mf128", "latent"), figures(tables, "mf", "latent"))
    tests = {
        "a: latent per measurement above 0": latent["low"] > 0,
        "b: each fold's mean above 0": all(f > 0 for f in folds),
        "c: encoder not wholly below 0": encoder["high"] >= 0,
        "d: tables' latent not wholly below 0": table["high"] >= 0,
    }
    reported = {
        f"{arm} {budget}": mean_of(fig[arm, budget], sorted(fig[arm, budget]))
        for arm in ("mf", "mf128") for budget in ("none", "latent", "full")
    }
    reported |= {f"{arm} {budget} by kind": {kind: mean_of(fig[arm, budget], names) for kind, names in FOLDS["kinds"].items()}
                 for arm in ("mf", "mf128") for budget in ("none", "latent", "full")}
    reported["full, mf128 − mf"] = difference(fig["mf128", "full"], fig["mf", "full"])
    reported["tables' encoder, mf128 − mf"] = difference(figures(tables, "mf128", "none"), figures(tables, "mf", "none"))
    reported["ΔE > 6"] = {f"{arm} {budget}": {m: round(v[1], 2) for m, v in fig[arm, budget].items() if v[1] > 6}
                          for arm in ("mf", "mf128") for budget in ("none", "latent", "full")}
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
