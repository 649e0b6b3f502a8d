"""Summarises ``compare_models.py`` reports again from their stored rows, without scoring anything (after a fix
to the summary: a table and a measurement of one name were once pooled in both groups).

    python research/studies/resummarise.py research/results/version-5/*/compare.json

Rewrites each report's ``summary`` and the ``compare.md`` beside it. The groups are ``measured`` and ``tables`` (the
rows say which is which); a report with groups of ``--group`` is refused, since their members are not stored.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from compare_models import conditions_markdown, markdown, summarise_conditions, variant

from frenbrdf.io.atomic import save_json, write_text

BUDGET_ORDER = ("none", "latent", "full")


def resummarise(path: Path) -> None:
    report = json.loads(path.read_text())
    rows = report["rows"]
    groups = {name: sorted({r["material"] for r in rows if r["group"] == name}) for name in ("measured", "tables")}
    groups = {name: members for name, members in groups.items() if members}
    if extra := {key.split(" @ ")[0] for key in report.get("summary", {})} - set(groups):
        raise SystemExit(f"{path}: has groups of --group ({sorted(extra)}); rerun compare_models.py instead")
    budgets = sorted({r["budget"] for r in rows}, key=BUDGET_ORDER.index)
    conditions = [(pattern, count) for pattern in report["patterns"] for count in report["samples"]]
    summary = summarise_conditions(rows, variant(next(iter(report["models"]))), groups, budgets, conditions)
    save_json(path, report | {"summary": summary})
    write_text(path.with_name("compare.md"),
               markdown(summary) if len(conditions) == 1 else conditions_markdown(summary, groups, budgets, conditions))


def main(argv=None) -> int:
    for path in map(Path, argv if argv is not None else sys.argv[1:]):
        resummarise(path)
        print(f"summarised {path} again")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
