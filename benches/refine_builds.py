"""Two builds of the native module, the weight stage of `full` refinement, timed in one process in alternating rounds.

    python benches/refine_builds.py BASE.so NEW.so [--rounds 15] [--threads 2] [--steps 100]

As benches/sht_builds.py does for the SHT: both builds (``lib_native.so`` from ``cargo build --release --features
python --lib``, copied aside) loaded under different module names, checked against each other, then timed with
``common.time_interleaved``. The workload is `full`'s: an NBRDF 6 → 64 → 64 → 3 refined against 8,000 samples
(4,000 random bins in both orders) in batches of 4,096, ``--steps`` Adam steps a call. Reported: NEW's time over
BASE's, per-round median and quartiles (below 1: NEW is faster), and the two builds' losses after 50 steps.
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sht_builds import builds_parser, load_builds, timed_ratio  # noqa: E402

WIDTHS = (6, 64, 64, 3)
SAMPLES, BATCH = 8000, 4096


def workload(steps: int, seed: int = 0):
    """The arguments of a fresh ``WeightFit`` and of one call of ``steps`` steps."""
    import numpy as np

    rng = np.random.default_rng(seed)
    tensors, decays = [], []
    for inputs, outputs in itertools.pairwise(WIDTHS):
        tensors += [rng.normal(0, 1 / np.sqrt(inputs), (outputs, inputs)).astype(np.float32),
                    rng.normal(0, 0.1, outputs).astype(np.float32)]
        decays += [1e-3, 0.0]
    coords = rng.uniform(-1, 1, (SAMPLES, WIDTHS[0])).astype(np.float32)
    values = np.stack([0.3 * coords[:, 0] + 0.1, np.abs(coords[:, 1]), 0.5 * coords[:, 2] ** 2], 1).astype(np.float32)
    cos_in = rng.uniform(0.05, 1, SAMPLES).astype(np.float32)
    return (tensors, decays, coords, values, cos_in, "l1"), np.full(steps, 3e-3, np.float32), \
        rng.integers(0, SAMPLES, (steps, BATCH))


def steps_of(module, arguments) -> list[float]:
    """The losses of one call from a fresh fit. (Every timed call starts afresh: thousands of steps on one fit drift
    into subnormal values, several times slower.)"""
    fit_arguments, rates, rows = arguments
    return module.WeightFit(*fit_arguments).run(rates, rows)


def main() -> None:
    parser = builds_parser(__doc__.split("\n\n")[0], rounds=15, threads=2)
    parser.add_argument("--steps", type=int, default=100, help="Adam steps a call")
    args = parser.parse_args()
    import numpy as np

    from common import cpu_model

    base, new = load_builds(args)
    check = workload(50)
    losses = [np.asarray(steps_of(module, check)) for module in (base, new)]
    agreement = float(np.abs(losses[1] - losses[0]).max() / np.abs(losses[0]).max())
    timed = workload(args.steps)
    rounds, ratio = timed_ratio(lambda: steps_of(base, timed), lambda: steps_of(new, timed), args.rounds)
    print(f"CPU: {cpu_model()}; {args.threads} thread(s); {args.steps} steps of {BATCH} of {SAMPLES} samples, "
          f"widths {WIDTHS}")
    print(f"BASE {rounds['first_median_s'] * 1e3 / args.steps:.3f} ms a step, NEW "
          f"{rounds['second_median_s'] * 1e3 / args.steps:.3f}; {ratio}; losses after 50 steps "
          f"{losses[0][-1]:.6g} and {losses[1][-1]:.6g} (largest relative difference {agreement:.1e})")


if __name__ == "__main__":
    main()
