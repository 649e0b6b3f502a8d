"""The latent-rate study's two readings (README.md).

    python research/results/latent-rate/decide.py explore OUT   # the candidate: OUT/{families,tables}-{random,devices}
    python research/results/latent-rate/decide.py judge OUT RATE   # the rule, RATE the candidate; OUT/measured too
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from budget_readings import changes, devices_mean, judged, measured, plain_group, rows_of  # noqa: E402

BASE = "latent"
RATES = ["0.015", "0.06", "0.1"]


def candidate(rate: str) -> str:
    return f"latent@latent_lr={rate}"


def explore(out: Path) -> None:
    """Each rate's four mean changes from 3e-2 (families, tables × random bins, the devices' mean) and their mean;
    the candidate is the rate with the highest, if above 0."""
    means = {}
    for rate in RATES:
        four = []
        for prefix in ("families", "tables"):
            random = rows_of(out / f"{prefix}-random")
            change = changes(random, "psnr", plain_group(random), BASE, candidate(rate))["merl-bins"]
            four.append(float(np.mean(list(change.values()))))
            four.append(float(np.mean(list(devices_mean(rows_of(out / f"{prefix}-devices"), "psnr", BASE,
                                                         candidate(rate)).values()))))
        means[rate] = float(np.mean(four))
        print(f"rate {rate}: families random {four[0]:+.2f}, devices {four[1]:+.2f}; tables random {four[2]:+.2f}, "
              f"devices {four[3]:+.2f}; mean {means[rate]:+.3f}")
    best = max(means, key=means.__getitem__)
    print(f"candidate: {best}" if means[best] > 0 else "no rate reads better than 3e-2: nothing is judged")


def judge(out: Path, rate: str) -> None:
    tests = {prefix: judged(out, prefix, BASE, candidate(rate)) for prefix in ("families", "tables")}
    rule = {"(a) families, random bins, above 0": tests["families"]["random psnr"]["low"] > 0,
            "(b) families, the devices' mean, not wholly below 0": tests["families"]["devices psnr"]["high"] > 0,
            "(c) tables, random bins, not wholly below 0": tests["tables"]["random psnr"]["high"] > 0,
            "(d) tables, the devices' mean, not wholly below 0": tests["tables"]["devices psnr"]["high"] > 0}
    if (out / "measured" / "compare.json").exists():
        rule["(e) the 19 measurements, not wholly below 0"] = measured(
            out, ["none", BASE, candidate(rate)], BASE, candidate(rate))["high"] > 0
    for name, passed in rule.items():
        print(f"{name}: {'passes' if passed else 'FAILS'}")
    verdict = all(rule.values()) and len(rule) == 5
    print(f"decision: {'the rate becomes ' + rate if verdict else 'the rate stays 3e-2'}")


def main(argv: list[str]) -> int:
    if len(argv) == 2 and argv[0] == "explore":
        explore(Path(argv[1]))
    elif len(argv) == 3 and argv[0] == "judge":
        judge(Path(argv[1]), argv[2])
    else:
        sys.exit(__doc__)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
