"""The latent-rate study's exploration (README.md): which rate would be judged. (Its judging readings and rule,
commit c4b7ef2, were removed unrun: no rate read better than 3e-2.)

    python research/results/latent-rate/decide.py explore OUT   # OUT/{families,tables}-{random,devices}
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from budget_readings import changes, devices_mean, plain_group, rows_of  # noqa: E402

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
            devices = rows_of(out / f"{prefix}-devices")
            per_pattern = changes(devices, "psnr", plain_group(devices), BASE, candidate(rate))
            four.append(float(np.mean(list(devices_mean(per_pattern).values()))))
        means[rate] = float(np.mean(four))
        print(f"rate {rate}: families random {four[0]:+.2f}, devices {four[1]:+.2f}; tables random {four[2]:+.2f}, "
              f"devices {four[3]:+.2f}; mean {means[rate]:+.3f}")
    best = max(means, key=means.__getitem__)
    print(f"candidate: {best}" if means[best] > 0 else "no rate reads better than 3e-2: nothing is judged")


def main(argv: list[str]) -> int:
    if len(argv) != 2 or argv[0] != "explore":
        sys.exit(__doc__)
    explore(Path(argv[1]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
