"""The real-encoders study's rule (README.md), from the rows of the attention-pooling study's ``compare.sh``.

    python research/results/real-encoders/decide.py OUT [CANDIDATE BASELINE]      (default: real mixed)

Per-material PSNR differences CANDIDATE − BASELINE, each the mean over its runs, with 95 % intervals: on the
measurements, the encoder averaged over seven readings (the six patterns at 1,500 samples in OUT/patterns and
random bins at 4,000 in OUT/random); on the tables, the encoder from 4,000 random bins. Prints both and the
verdict (better, worse or within noise); writes OUT/decision.json.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.io.atomic import save_json

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import DEVICE_PATTERNS, paired_difference, print_intervals  # noqa: E402


def main(argv=None) -> int:
    args = argv if argv is not None else sys.argv[1:]
    out, candidate, baseline = Path(args[0]), *(args[1:3] or ("real", "mixed"))
    patterns, random = ((json.loads((out / name / "compare.json").read_text())["rows"]) for name in ("patterns", "random"))
    tests = {
        "measured_seven_readings": paired_difference(patterns + random, candidate, baseline,
                                                     ("merl-bins", *DEVICE_PATTERNS), group="measured"),
        "tables_encoder_random_4000": paired_difference(random, candidate, baseline, ("merl-bins",)),
    }
    intervals = [(test["low"], test["high"]) for test in tests.values()]
    if any(high < 0 for _, high in intervals):
        verdict = "worse"
    elif intervals[0][0] > 0 and intervals[1][1] > 0:
        verdict = "better"
    else:
        verdict = "within noise"
    save_json(out / "decision.json", {"candidate": candidate, "baseline": baseline, **tests, "verdict": verdict})
    print_intervals(tests)
    print(f"{candidate} against {baseline}: {verdict}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
