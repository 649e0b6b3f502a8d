"""fold-tie's rule (README.md): `mftie` (seed 0 of each fold, the seam tie at 0.5) against the recipe's same-seed fold
runs, per measurement over the 19 and per table over the 40; and its seam steps against the shipped model's.

    python research/results/fold-tie/decide.py OUT

OUT holds read.sh's `mftie-fF-s0/compare.json`, `tables/compare.json` and `seam-fF.json`. Writes OUT/decision.json
and prints the rule's tests and what is reported beside them.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

RESULTS = Path(__file__).resolve().parent.parent
KINDS = json.loads((RESULTS.parent / "studies" / "measured_folds" / "folds.json").read_text())["kinds"]
#: The recipe's seed-0 fold runs trained on this kind of machine (encoder and `latent` on the 19).
HERE_RUNS = RESULTS / "latent-native" / "out" / "measured" / "compare.json"
#: The same seed trained on an Intel Xeon (real-in-data): `full` on the 19, encoder and `latent` on the 40 tables.
XEON_RUNS = RESULTS / "real-in-data" / "out"
#: The shipped model's seam steps on the 19 (research/results/seam).
SHIPPED_SEAM = RESULTS / "seam" / "seam.json"
HUE_LOST = 6.0

sys.path.insert(0, str(RESULTS / "real-in-data"))
from seeds import mean as mean_of  # noqa: E402  ("PSNR / ΔE" over the names a figure has)
from seeds import per_material  # noqa: E402  (material → (PSNR, ΔE, runs))


def rows_of(paths) -> list[dict]:
    return [row for path in paths for row in json.loads(Path(path).read_text())["rows"]]


def change(new: dict, old: dict, metric: int) -> dict:
    names = sorted(new.keys() & old.keys())
    return paired_interval([new[m][metric] - old[m][metric] for m in names])


def text(d: dict) -> str:
    return f"{d['mean']:+.2f} [{d['low']:+.2f}, {d['high']:+.2f}] (n {d['n']})"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path)
    args = parser.parse_args(argv)
    tied_rows = rows_of(sorted(args.out.glob("mftie-f*-s0/compare.json")))
    here_rows, xeon_rows = rows_of([HERE_RUNS]), rows_of([XEON_RUNS / "measured" / "compare.json"])
    tied = {b: per_material(tied_rows, "mftie", b) for b in ("none", "latent", "full")}
    base = {b: per_material(here_rows, "mf", b) for b in ("none", "latent")} | {"full": per_material(xeon_rows, "mf", "full")}
    if any(len(tied[b]) != 19 for b in tied):
        raise SystemExit(f"mftie read {[len(tied[b]) for b in tied]} measurements (encoder, latent, full); expected 19")
    tables = rows_of([args.out / "tables" / "compare.json", XEON_RUNS / "tables" / "compare.json"])
    tables_tied = {b: per_material(tables, "mftie", b) for b in ("none", "latent")}
    tables_base = {b: per_material(tables, "mf", b) for b in ("none", "latent")}

    seams = {}
    for path in sorted(args.out.glob("seam-f*.json")):
        seams |= json.loads(path.read_text())["materials"]
    shipped = json.loads(SHIPPED_SEAM.read_text())["summary"]
    steps = {b: {s: float(np.median([row[b][s] for row in seams.values()])) for s in ("median", "p90")}
             for b in ("none", "latent", "full")}

    readings = {b: {"psnr": change(tied[b], base[b], 0), "delta_e": change(tied[b], base[b], 1)} for b in tied}
    table_latent = change(tables_tied["latent"], tables_base["latent"], 0)
    tests = {
        "harmless: encoder PSNR's lower end above -0.5 dB": readings["none"]["psnr"]["low"] > -0.5,
        "harmless: encoder's mean ΔE change below +0.5": readings["none"]["delta_e"]["mean"] < 0.5,
        "harmless: latent PSNR's lower end above -0.5 dB": readings["latent"]["psnr"]["low"] > -0.5,
        "harmless: latent's mean ΔE change below +0.5": readings["latent"]["delta_e"]["mean"] < 0.5,
        "harmless: tables' latent lower end above -0.5 dB": table_latent["low"] > -0.5,
        "removes the seam: encoder's median step at most a quarter of the shipped model's":
            len(seams) == 19 and steps["none"]["median"] <= shipped["none"]["median"] / 4,
        "removes the seam: latent's median step at most a quarter of the shipped model's":
            len(seams) == 19 and steps["latent"]["median"] <= shipped["latent"]["median"] / 4,
    }
    reported = {
        "figures (PSNR / ΔE), mftie and the baseline": {b: [mean_of(tied[b], tied[b]), mean_of(base[b], base[b])]
                                                         for b in tied},
        "by kind, mftie and the baseline": {b: {k: [mean_of(tied[b], n), mean_of(base[b], n)] for k, n in KINDS.items()}
                                           for b in tied},
        "tables (PSNR / ΔE), mftie and mf seed 0 (Xeon)": {b: [mean_of(tables_tied[b], tables_tied[b]),
                                                             mean_of(tables_base[b], tables_base[b])]
                                                         for b in ("none", "latent")},
        "tables' encoder change": change(tables_tied["none"], tables_base["none"], 0),
        "seam steps (median / p90 over the 19), mftie and the shipped model": {
            b: [steps[b], shipped[b]] for b in ("none", "latent", "full")},
        f"ΔE > {HUE_LOST:g}": {b: {m: round(v[1], 2) for m, v in tied[b].items() if v[1] > HUE_LOST} for b in tied},
        "irid_flake_paint2_rgb": {b: [tied[b]["irid_flake_paint2_rgb"][:2], base[b]["irid_flake_paint2_rgb"][:2]]
                                  for b in tied},
    }
    decision = {"harmless": all(v for k, v in tests.items() if k.startswith("harmless")),
                "removes the seam": all(v for k, v in tests.items() if k.startswith("removes")),
                "tests": tests, "readings": readings, "tables' latent": table_latent, "reported": reported}
    decision["passes"] = decision["harmless"] and decision["removes the seam"]
    (args.out / "decision.json").write_text(json.dumps(decision, indent=1, ensure_ascii=False) + "\n")
    show(decision, {"latent": table_latent})


def show(decision: dict, tables: dict[str, dict]) -> None:
    """Prints a decision's tests, its readings on the 19 and on the tables (budget → reading), what it reports."""
    for name, passed in decision["tests"].items():
        print(f"{'pass' if passed else 'FAIL'}  {name}")
    for budget, reading in decision["readings"].items():
        print(f"{budget}: PSNR {text(reading['psnr'])}, ΔE {text(reading['delta_e'])}")
    for budget, reading in tables.items():
        print(f"tables' {budget}: {text(reading)}")
    for name, value in decision["reported"].items():
        print(name, json.dumps(value, ensure_ascii=False))
    print("the rule:", "passes" if decision["passes"] else "fails")


if __name__ == "__main__":
    main()
