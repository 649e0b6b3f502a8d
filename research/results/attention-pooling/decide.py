"""The attention-pooling study's rule (README.md), from the rows of ``compare.sh``'s two comparisons.

    python research/results/attention-pooling/decide.py OUT CANDIDATE BASELINE

On the ``tables`` group, encoder only, each variant's PSNR per material the mean over its runs: (a) the per-material
difference CANDIDATE − BASELINE averaged over the five device patterns at 1,500 samples (OUT/patterns), its 95 %
interval above 0; (b) the difference from 4,000 random bins (OUT/random), its interval not wholly below 0. Prints
both and whether the candidate passes; writes OUT/decision-CANDIDATE.json.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


from frenbrdf.io.atomic import save_json

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import DEVICE_PATTERNS, paired_difference, print_intervals  # noqa: E402


def main(argv=None) -> int:
    out, candidate, baseline = (argv or sys.argv[1:])[:3]
    rows = {name: json.loads((Path(out) / name / "compare.json").read_text())["rows"] for name in ("patterns", "random")}
    devices = paired_difference(rows["patterns"], candidate, baseline, DEVICE_PATTERNS)
    random_bins = paired_difference(rows["random"], candidate, baseline, ("merl-bins",))
    decision = {"candidate": candidate, "baseline": baseline, "devices_1500": devices, "random_bins_4000": random_bins,
                "passes": bool(devices["low"] > 0 and random_bins["high"] > 0)}
    save_json(Path(out) / f"decision-{candidate}.json", decision)
    print_intervals({name: decision[name] for name in ("devices_1500", "random_bins_4000")})
    print(f"{candidate} against {baseline}: {'passes' if decision['passes'] else 'does not pass'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
