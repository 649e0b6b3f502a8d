"""The device-specialists study's rule (README.md), from the rows of the attention-pooling study's ``compare.sh``.

    python research/results/device-specialists/decide.py OUT CANDIDATE BASELINE

On the ``tables`` group (the families, with FAMILIES set), each per-material PSNR difference CANDIDATE − BASELINE
with its 95 % interval: (a) the encoder averaged over the five device patterns at 1,500 samples (OUT/patterns),
above 0; (b) the encoder from 4,000 random bins (OUT/random), not wholly below 0; (c) ``latent`` from the same
4,000 random bins, not wholly below 0. Prints the three and whether the candidate passes; writes
OUT/decision-CANDIDATE.json.
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
    tests = {
        "a_devices_1500": paired_difference(rows["patterns"], candidate, baseline, DEVICE_PATTERNS),
        "b_encoder_random_4000": paired_difference(rows["random"], candidate, baseline, ("merl-bins",)),
        "c_latent_random_4000": paired_difference(rows["random"], candidate, baseline, ("merl-bins",), "latent"),
    }
    # "not wholly below 0": an interval that ends at 0 (the same results for every material) is not below it
    passes = (tests["a_devices_1500"]["low"] > 0 and tests["b_encoder_random_4000"]["high"] >= 0
              and tests["c_latent_random_4000"]["high"] >= 0)
    save_json(Path(out) / f"decision-{candidate}.json",
              {"candidate": candidate, "baseline": baseline, **tests, "passes": bool(passes)})
    print_intervals(tests)
    print(f"{candidate} against {baseline}: {'passes' if passes else 'does not pass'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
