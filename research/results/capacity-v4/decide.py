"""The capacity re-choice's rule (README.md), from the rows of the attention-pooling study's ``compare.sh``
(run with LATENT=1).

    python research/results/capacity-v4/decide.py OUT [CANDIDATE BASELINE]      (default: big small)

From 4,000 random bins (OUT/random), per-material differences CANDIDATE − BASELINE, each the mean over its runs,
with 95 % intervals: on the tables, encoder PSNR, `latent` PSNR and encoder ΔE; on the measurements, the mean
encoder and `latent` PSNR of each arm. Prints them and the verdict (better, worse or within noise); writes
OUT/decision.json.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.io.atomic import save_json

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import paired_difference, print_intervals  # noqa: E402

RANDOM_BINS = ("merl-bins",)


def main(argv=None) -> int:
    args = argv if argv is not None else sys.argv[1:]
    out, candidate, baseline = Path(args[0]), *(args[1:3] or ("big", "small"))
    rows = json.loads((out / "random" / "compare.json").read_text())["rows"]
    tables = {
        "encoder_psnr": paired_difference(rows, candidate, baseline, RANDOM_BINS),
        "latent_psnr": paired_difference(rows, candidate, baseline, RANDOM_BINS, "latent"),
        "encoder_delta_e": paired_difference(rows, candidate, baseline, RANDOM_BINS, metric="delta_e"),
    }
    measured = {budget: paired_difference(rows, candidate, baseline, RANDOM_BINS, budget, group="measured")
                for budget in ("none", "latent")}
    psnr = (tables["encoder_psnr"], tables["latent_psnr"])
    if any(test["high"] < 0 for test in psnr):
        verdict = "worse"
    elif (any(test["low"] > 0 for test in psnr) and tables["encoder_delta_e"]["low"] <= 0
          and all(test["mean"] >= 0 for test in measured.values())):
        verdict = "better"
    else:
        verdict = "within noise"
    save_json(out / "decision.json", {"candidate": candidate, "baseline": baseline, "tables": tables,
                                      "measured": measured, "verdict": verdict})
    print_intervals({**{f"tables {k}": v for k, v in tables.items()}, **{f"measured {k}": v for k, v in measured.items()}})
    print(f"{candidate} against {baseline}: {verdict}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
