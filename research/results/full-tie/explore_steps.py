"""full-tie's exploration (before its protocol): the seam step of `full` at several tie weights on bank materials.

    python research/results/full-tie/explore_steps.py BANK/*.binary > research/results/full-tie/explore/steps.txt
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
import seam  # noqa: E402

import frenbrdf  # noqa: E402
from frenbrdf.models.reconstruct import refine_config  # noqa: E402

TIES = (0.0, 0.03, 0.1, 0.3, 1.0)


def main() -> None:
    model = frenbrdf.Model.pretrained()
    side, other = seam.seam_pairs()
    steps: dict[float, list[dict]] = {tie: [] for tie in TIES}
    for path in sys.argv[1:]:
        samples = frenbrdf.read_samples(path, samples=4000, seed=0)
        for tie in TIES:
            config = dataclasses.replace(refine_config("full"), tie=tie)
            result = model.reconstruct(samples.values, (samples.wi, samples.wo), refine=config)
            steps[tie].append(seam.jumps(result.nbrdf, side, other))
    for tie in TIES:
        print(f"tie {tie:g}: median of the materials' median steps {np.median([s['median'] for s in steps[tie]]):.4f}, "
              f"of their 90th percentiles {np.median([s['p90'] for s in steps[tie]]):.4f}")


if __name__ == "__main__":
    main()
