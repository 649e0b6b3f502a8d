"""What an encoding costs with one packed model against another, timed in alternating rounds.

    python benches/encode_cost.py BASE [CANDIDATE] [--samples 1500 4000] [--rounds 11] [--threads 1]

BASE and CANDIDATE are packed models' folders (``release/pack_*.py --dest``) or ``pretrained`` (the default
candidate). Each count draws uniform pairs of one procedural material (``frenbrdf.data.synth``, seed 0); both models
encode the same samples (``Model.encode``: the encoders, their choice and any second looks). Prints per count the median
seconds of each and the median ratio candidate / base, with its quartiles (``common.time_interleaved``).
"""

from __future__ import annotations

import argparse
from functools import partial

import numpy as np
import torch

from common import time_interleaved
from frenbrdf import Model
from frenbrdf.data.analytic import evaluate
from frenbrdf.data.synth import material_bank
from frenbrdf.io.patterns import sample_pattern


def load(name: str) -> Model:
    return Model.pretrained(None if name == "pretrained" else name)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("base")
    parser.add_argument("candidate", nargs="?", default="pretrained")
    parser.add_argument("--samples", type=int, nargs="+", default=[1500, 4000])
    parser.add_argument("--rounds", type=int, default=11)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    base, candidate = load(args.base), load(args.candidate)
    material = material_bank(1, seed=0)[0]
    for count in args.samples:
        directions = sample_pattern("uniform", count, np.random.default_rng(0))
        values = evaluate(material, *directions)
        timed = time_interleaved(partial(base.encode, values, directions),
                                 partial(candidate.encode, values, directions), args.rounds)
        summary = timed.ratio_summary()
        low, high = summary["quartiles"]
        print(f"{count} samples: base {1e3 * summary['first_median_s']:.1f} ms, candidate "
              f"{1e3 * summary['second_median_s']:.1f} ms; candidate / base {summary['median']:.2f}× "
              f"(quartiles {low:.2f}–{high:.2f}, {summary['rounds']} rounds, {args.threads} thread(s))")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
