"""One summary of several ``compare_models.py`` scorings of the same materials (evaluate.sh runs two halves of
the runs side by side): their rows together, summarised per pattern × count against ``paper-mean``, the
measurements also by kind, then the decision (decide.py).

    python research/studies/sampling_patterns/merge.py A/compare.json B/compare.json --out DIR
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]  # decide, compare_models
import compare_models  # noqa: E402
import decide  # noqa: E402

from frenbrdf.io.atomic import save_json, write_text  # noqa: E402

BASELINE = "paper-mean"
#: The kinds of the real measurements (../shared/data/rgl-measured/README.md, grouped as issue 48 reports them):
#: one table with the folds of the real-measurements study.
KINDS = json.loads((Path(__file__).resolve().parents[1] / "measured_folds" / "folds.json").read_text())["kinds"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("reports", nargs="+")
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)
    reports = [json.loads(Path(path).read_text()) for path in args.reports]
    rows = [row for report in reports for row in report["rows"]]
    conditions = list(dict.fromkeys((r["pattern"], r["count"]) for r in rows))
    budgets = list(dict.fromkeys(r["budget"] for r in rows))
    groups = {group: sorted({r["material"] for r in rows if r["group"] == group}) for group in ("tables", "measured")}
    scored = set(groups["measured"])
    groups |= {f"measured: {kind}": [m for m in members if m in scored] for kind, members in KINDS.items()}
    summary = compare_models.summarise_conditions(rows, BASELINE, groups, budgets, conditions)
    out = Path(args.out)
    merged = {"runs": [report["run"] for report in reports],
              "models": {k: v for report in reports for k, v in report["models"].items()},
              "trained_on": sorted({pair for report in reports for pair in report["trained_on"]}),
              "rows": rows, "summary": summary}
    save_json(out / "compare.json", merged)
    write_text(out / "compare.md", compare_models.conditions_markdown(summary, groups, budgets, conditions))
    return decide.main([str(out / "compare.json")])


if __name__ == "__main__":
    raise SystemExit(main())
