"""The project's SHT workload, ours against shtns, in one process and in alternating rounds.

    python benches/peers/sht_interleaved.py [--threads 1] [--rounds 21] [--json results.json]

``sht_peers.py`` times each library in its own process, one after the other; on a virtual
machine whose speed drifts by 10–25 % within minutes, that drift lands in the ratio. Here
both libraries are loaded in one process (192 maps, Gauss–Legendre 90 × 180, lmax 89, the
same plans as ``sht_peers.py``: ``sht_setup.Frenbrdf`` and ``sht_setup.Shtns``), each is
first checked against the other on the same maps, and then ours (float64 and float32) and
shtns (float64) are timed in alternating rounds (``common.time_interleaved``: each round the
best of three calls of each). Reported: per-round ratios ours / shtns in maps/s, their
median, quartiles and range. The thread counts are set before the libraries are imported.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--json", type=Path, help="also write the results here")
    args = parser.parse_args()
    for variable in ("RAYON_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[variable] = str(args.threads)

    sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]
    import numpy as np
    from sht_setup import Frenbrdf, Shtns

    from common import cpu_model, time_interleaved
    from frenbrdf.io.atomic import save_json

    nlat, nlon, lmax, batch = 90, 180, 89, 192
    maps = np.random.default_rng(0).standard_normal((batch, nlat, nlon))
    shtns = Shtns(args.threads).plan(nlat, nlon, lmax, "gauss", "float64")
    theirs_input = shtns.prepare(maps)
    reference = shtns.to_lm(shtns.analysis(theirs_input))
    results = {"cpu": cpu_model(), "threads": args.threads, "maps": batch, "grid": [nlat, nlon], "lmax": lmax}
    print(f"CPU: {results['cpu']}; {args.threads} thread(s); {batch} maps {nlat} x {nlon}, lmax {lmax}")
    for dtype in ("float64", "float32"):
        ours = Frenbrdf(args.threads).plan(nlat, nlon, lmax, "gauss", dtype)
        ours_input = ours.prepare(maps)
        error = np.abs(ours.to_lm(ours.analysis(ours_input)) - reference).max() / np.abs(reference).max()
        if error > (1e-5 if dtype == "float32" else 1e-10):
            sys.exit(f"ours {dtype} differs from shtns by {error:.1e} (relative): not timed")
        rounds = time_interleaved(lambda plan=ours, maps=ours_input: plan.analysis(maps),
                                  lambda: shtns.analysis(theirs_input), args.rounds).ratio_summary()
        results[dtype] = {**rounds, "error_against_shtns": float(error),
                          "ours_maps_per_s": batch / rounds["first_median_s"],
                          "shtns_maps_per_s": batch / rounds["second_median_s"]}
        print(f"ours {dtype}: {results[dtype]['ours_maps_per_s']:,.0f} maps/s, shtns float64 "
              f"{results[dtype]['shtns_maps_per_s']:,.0f} maps/s in the same rounds; ours / shtns over "
              f"{rounds['rounds']} rounds: median {rounds['median']:.2f}x (quartiles {rounds['quartiles'][0]:.2f}-"
              f"{rounds['quartiles'][1]:.2f}x, range {rounds['range'][0]:.2f}-{rounds['range'][1]:.2f}x); "
              f"agreement {error:.1e}")
    if args.json:
        save_json(args.json, results)  # atomically


if __name__ == "__main__":
    main()
