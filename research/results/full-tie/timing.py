"""Seconds of `full` with and without the tie on real measurements, interleaved, one process (full-tie's (c)).

    python research/results/full-tie/timing.py ../shared/data/rgl-measured/*.bsdf [--tie 0.1] [--repeats 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

import frenbrdf
from frenbrdf.models.reconstruct import refine_config


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("measurements", nargs="+", type=Path)
    parser.add_argument("--tie", type=float, default=0.1)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    model = frenbrdf.Model.pretrained()
    budgets = {"full": refine_config("full"), f"full@tie={args.tie:g}": dataclasses.replace(refine_config("full"),
                                                                                            tie=args.tie)}
    samples = [frenbrdf.read_samples(path, samples=4000, seed=0) for path in args.measurements]
    model.reconstruct(samples[0].values[:100], (samples[0].wi[:100], samples[0].wo[:100]), refine="full")  # warm-up
    best: dict[str, list[float]] = {name: [np.inf] * len(samples) for name in budgets}
    for _ in range(args.repeats):
        for index, sample in enumerate(samples):
            for name, config in budgets.items():
                start = time.perf_counter()
                model.reconstruct(sample.values, (sample.wi, sample.wo), refine=config)
                best[name][index] = min(best[name][index], time.perf_counter() - start)
    means = {name: float(np.mean(seconds)) for name, seconds in best.items()}
    for name, seconds in means.items():
        print(f"{name}: mean {seconds:.3f} s over {len(samples)} materials, best of {args.repeats}")
    tied, untied = means[f"full@tie={args.tie:g}"], means["full"]
    print(f"ratio {tied / untied:.3f}")


if __name__ == "__main__":
    main()
