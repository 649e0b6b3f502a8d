"""Two builds of the native module, the float32 `.bsdf` evaluator, timed in one process in alternating rounds.

    python benches/bsdf_builds.py BASE.so NEW.so [--rounds 15] [--threads 2] [--n 1000000] [--file F.bsdf]

As benches/sht_builds.py does for the SHT: both builds (``lib_native.so`` from ``cargo build --release --features
python --lib``, copied aside) loaded under different module names, checked against each other on the same pairs,
then timed with ``common.time_interleaved`` on the pairs of benches/peers/bsdf_eval.py (golden yellow, 1 M pairs).
Reported: NEW's time over BASE's, per-round median and quartiles (below 1: NEW is faster).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parent / "peers")]
from bsdf_eval import DEFAULT_FILE, direction_pairs  # noqa: E402

from sht_builds import builds_parser, load_builds, timed_ratio  # noqa: E402


def main() -> None:
    parser = builds_parser(__doc__.split("\n\n")[0], rounds=15, threads=2)
    parser.add_argument("--n", type=int, default=1_000_000, help="direction pairs a call")
    parser.add_argument("--file", type=Path, default=DEFAULT_FILE, help="an RGB .bsdf file of the RGL database")
    args = parser.parse_args()
    import numpy as np

    from common import cpu_model

    measurements = [module.BsdfMeasurement.read(args.file) for module in load_builds(args)]
    wi, wo = direction_pairs(args.n)
    expected, got = (np.asarray(m.eval(wi, wo)) for m in measurements)
    error = float(np.abs(got - expected).max() / np.abs(expected).max())
    rounds, ratio = timed_ratio(lambda: measurements[0].eval(wi, wo), lambda: measurements[1].eval(wi, wo),
                                args.rounds)
    print(f"CPU: {cpu_model()}; {args.threads} thread(s); {args.n:,} pairs of {args.file.name}")
    print(f"BASE {args.n / rounds['first_median_s'] / 1e6:.1f} M/s, NEW {args.n / rounds['second_median_s'] / 1e6:.1f}; "
          f"{ratio}; largest difference {error:.1e} of the largest value")


if __name__ == "__main__":
    main()
