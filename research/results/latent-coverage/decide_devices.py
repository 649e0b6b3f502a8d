"""Amendment 1's rule (README.md): per family, coverage weights minus `latent` through the five device patterns,
their mean and each pattern, 95 % intervals over the families.

    python research/results/latent-coverage/decide_devices.py OUT-12/families-devices/compare.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.evaluation.statistics import paired_interval

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "latent-steps"))
import decide as steps  # noqa: E402

steps.CANDIDATE = "latent@coverage_k=32"

if __name__ == "__main__":
    rows = json.loads(Path(sys.argv[1]).read_text())["rows"]
    for metric in ("psnr", "delta_e"):
        by_pattern = steps.differences(rows, metric)
        materials = sorted(set.intersection(*(set(d) for d in by_pattern.values())))
        mean = paired_interval([np.mean([d[m] for d in by_pattern.values()]) for m in materials])
        print(f"five devices' mean, {metric}: {steps.interval_text(mean)}")
        for (_, pattern), differences in by_pattern.items():
            print(f"{pattern}, {metric}: {steps.interval_text(paired_interval(list(differences.values())))}")
        if metric == "psnr":
            print(f"rule: {'on where the samples come from a device' if mean['low'] > 0 else 'stays off'}")
