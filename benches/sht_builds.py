"""Two builds of the native module, one SHT workload, timed in one process in alternating rounds.

    python benches/sht_builds.py BASE.so NEW.so [--dtype float32] [--rounds 21] [--threads 1] [--batch 192]

For changes to the SHT's kernels that move its speed by a few percent: on a virtual machine two
processes run minutes apart differ by more than that. Both builds (``lib_native.so`` from
``cargo build --release --features python --lib``, copied aside) are loaded under different module
names, checked against each other on the same maps, then timed with ``common.time_interleaved`` on
the project's workload (192 maps, Gauss–Legendre 90 × 180, lmax 89; ``--batch`` another count of
maps). Reported: NEW's time over BASE's, per-round median and quartiles (below 1: NEW is faster).
"""

from __future__ import annotations

import argparse
import importlib.machinery
import importlib.util
import os
import sys
from pathlib import Path


def load(path: Path, name: str):
    """The extension module at ``path``, imported as ``name``."""
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    if spec is None:
        sys.exit(f"{path} is not a loadable extension module")
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def builds_parser(description: str, *, rounds: int, threads: int) -> argparse.ArgumentParser:
    """The arguments of every two-builds harness: BASE.so NEW.so, ``--rounds``, ``--threads``."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("base", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--rounds", type=int, default=rounds)
    parser.add_argument("--threads", type=int, default=threads)
    return parser


def load_builds(args: argparse.Namespace) -> tuple:
    """Both builds, each under the name its PyInit symbol expects in a package of its own, on pools of
    ``args.threads`` (set before either build starts its pool)."""
    os.environ["RAYON_NUM_THREADS"] = str(args.threads)
    return tuple(load(path, f"{tag}._native") for tag, path in (("base", args.base), ("new", args.new)))


def timed_ratio(base_call, new_call, rounds: int) -> tuple[dict, str]:
    """``common.time_interleaved``'s summary of the two calls (second / first: NEW's time over BASE's) and its line."""
    from common import time_interleaved

    summary = time_interleaved(base_call, new_call, rounds).ratio_summary()
    low, high = summary["quartiles"]
    return summary, (f"NEW's time / BASE's over {summary['rounds']} rounds: median {summary['median']:.3f} "
                     f"(quartiles {low:.3f}-{high:.3f})")


def main() -> None:
    parser = builds_parser(__doc__.split("\n\n")[0], rounds=21, threads=1)
    parser.add_argument("--dtype", choices=("float32", "float64"), default="float32")
    parser.add_argument("--batch", type=int, default=192, help="maps per call")
    args = parser.parse_args()

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import numpy as np

    from common import cpu_model

    base, new = load_builds(args)
    nlat, nlon, lmax, batch = 90, 180, 89, args.batch
    maps = np.random.default_rng(0).standard_normal((batch, nlat * nlon)).astype(args.dtype)
    plans = [module.ShtPlan(nlat, nlon, lmax, "gauss", args.dtype) for module in (base, new)]
    expected, got = (np.asarray(plan.analysis(maps)) for plan in plans)
    error = np.abs(got - expected).max() / np.abs(expected).max()
    if error > (1e-5 if args.dtype == "float32" else 1e-12):
        sys.exit(f"the builds disagree by {error:.1e} (relative): not timed")
    rounds, ratio = timed_ratio(lambda: plans[0].analysis(maps), lambda: plans[1].analysis(maps), args.rounds)
    print(f"CPU: {cpu_model()}; {args.threads} thread(s); {args.dtype}; {batch} maps {nlat} x {nlon}, lmax {lmax}")
    print(f"BASE {batch / rounds['first_median_s']:,.0f} maps/s, NEW {batch / rounds['second_median_s']:,.0f}; "
          f"{ratio}; agreement {error:.1e}")


if __name__ == "__main__":
    main()
