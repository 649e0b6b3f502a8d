"""The fold study's decisions, by the rules fixed before its runs (research/results/measured-folds).

    python research/studies/measured_folds/decide.py OUT/measured/compare.json OUT/tables/compare.json

Encoder only (budget ``none``), each variant's PSNR per material the mean over its runs that did not train on
that material:

1. *Measurements*: ``measured`` replaces ``fits`` if the per-measurement difference has its 95 % interval
   over the 19 above 0 and the tables' difference is not wholly below 0.
2. *Families*: ``families`` replaces ``measured`` by the same test against it.
3. *Together* (the replication, whose runs have no ``measured`` arm): ``families`` (the measurements and the
   families) replaces ``fits`` by the same test.

Prints both tests and writes ``decision.json`` beside the first file.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import save_json

#: The tests main() may run, in order.
TESTS = ("measurements", "families", "together")


def per_material(rows: list[dict], variant: str, budget: str = "none") -> dict[str, float]:
    """Material → the variant's PSNR at ``budget``, averaged over its runs."""
    mine = [r for r in rows if r["model"].split("/")[0] == variant and r["budget"] == budget]
    return {m: float(np.mean([r["psnr"] for r in mine if r["material"] == m])) for m in {r["material"] for r in mine}}


def difference(rows: list[dict], candidate: str, incumbent: str) -> dict:
    new, old = per_material(rows, candidate), per_material(rows, incumbent)
    return paired_interval([new[m] - old[m] for m in sorted(new.keys() & old.keys())])


def test(measured: list[dict], tables: list[dict], candidate: str, incumbent: str) -> dict:
    out = {"measurements": difference(measured, candidate, incumbent),
           "tables": difference(tables, candidate, incumbent)}
    out["wins"] = bool(out["measurements"]["low"] > 0 and out["tables"]["high"] > 0)
    return out


def main(argv=None) -> int:
    measured_path, tables_path = (Path(a) for a in (argv or sys.argv[1:]))
    measured, tables = (json.loads(p.read_text())["rows"] for p in (measured_path, tables_path))
    variants = {r["model"].split("/")[0] for r in measured}
    decision = {}
    if "measured" in variants:
        decision["measurements"] = test(measured, tables, "measured", "fits")
        if "families" in variants:
            decision["families"] = test(measured, tables, "families", "measured")
    elif "families" in variants:
        decision["together"] = test(measured, tables, "families", "fits")
    decision["ships"] = [name for name in TESTS if decision.get(name, {}).get("wins")]
    save_json(measured_path.with_name("decision.json"), decision)
    for name in TESTS:
        if name in decision:
            print(name, {key: (f"{v['mean']:+.2f} [{v['low']:+.2f}, {v['high']:+.2f}] (n={v['n']})"
                               if isinstance(v, dict) else v) for key, v in decision[name].items()})
    print("joins the shipped model's data:", decision["ships"] or "nothing")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
