"""Reciprocity of decoded BRDFs with and without the fold of D (docs/method.md §1), and what
the fold costs the published NBRDF fits.

    python research/studies/reciprocity.py [RUN_DIR ...] [--data DIR] [--published DIR]

For each run, the test materials are encoded (4000 samples) and decoded; at 20,000 random
direction pairs above the horizon, |ln f(ω_i, ω_o) − ln f(ω_o, ω_i)| is reported for the
network fed D unfolded (as before the fold) and folded (as now). For the published fits
(``../shared/data/merl-nbrdf``) it reports |Δ ln(1 + f)| between folded and unfolded D.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import frenbrdf
from frenbrdf.data.nbrdf_import import keras_nbrdf
from frenbrdf.evaluation.evaluate import load_runs
from frenbrdf.io.keras import read_keras_nbrdf
from frenbrdf.io.merl import N_BINS
from frenbrdf.io.sampling import sample_bins
from frenbrdf.models.nbrdf import nbrdf_coordinates

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
import common  # noqa: E402


def pairs(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    wi, wo = (common.unit_vectors(rng, n, hemisphere=True) for _ in range(2))
    keep = (wi[:, 2] > 0.05) & (wo[:, 2] > 0.05)
    return wi[keep], wo[keep]


def unfolded_inputs(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The NBRDF input as it was before the fold: D as half_diff_vectors gives it."""
    _, d = frenbrdf.half_diff_vectors(wi, wo)
    return np.concatenate([nbrdf_coordinates(wi, wo)[:, :3], d], axis=-1)


def log_gap(one: np.ndarray, other: np.ndarray, floor: float = 1e-3) -> np.ndarray:
    return np.abs(np.log(np.maximum(one, floor)) - np.log(np.maximum(other, floor))).mean(axis=-1)


def run_gaps(run_dir: str, data: str | None, wi: np.ndarray, wo: np.ndarray) -> dict:
    loaded = load_runs([run_dir], data)
    model = next(iter(loaded.models.values()))
    rng = np.random.default_rng(0)
    before, after = [], []
    for name in loaded.test:
        table = frenbrdf.read_merl(loaded.files[name])
        bins = sample_bins(table, rng, 4000)
        from frenbrdf.io.sampling import bin_directions

        nbrdf = model.decode(model.encode(table.reshape(3, N_BINS)[:, bins].T, bin_directions(bins)))[0]
        reference = nbrdf.mapping.reference_at(wi, wo)
        unfolded = [nbrdf.mapping.inverse(nbrdf.mapped(unfolded_inputs(a, b)), reference) for a, b in
                    ((wi, wo), (wo, wi))]
        before.append(np.median(log_gap(*unfolded)))
        after.append(np.median(log_gap(nbrdf(wi, wo), nbrdf(wo, wi))))
    return {"run": run_dir, "materials": len(before), "median_before": float(np.mean(before)),
            "max_before": float(np.max(before)), "median_after": float(np.mean(after))}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="*", help="training run folders")
    parser.add_argument("--data", help="materials folder of the runs (default: the one they recorded)")
    parser.add_argument("--published", type=Path,
                        default=Path(__file__).resolve().parents[2] / "shared" / "data" / "merl-nbrdf")
    args = parser.parse_args()
    wi, wo = pairs(20_000)
    for run in args.runs:
        r = run_gaps(run, args.data, wi, wo)
        print(f"{r['run']}: {r['materials']} test materials, median |ln f(wi,wo) - ln f(wo,wi)| per material "
              f"(mean over materials): unfolded {r['median_before']:.3f} (worst {r['max_before']:.3f}), "
              f"folded {r['median_after']:.2g}")
    files = sorted(args.published.glob("*.h5"))
    if files:
        folded, unfolded = nbrdf_coordinates(wi, wo), unfolded_inputs(wi, wo)
        moved = np.abs(folded - unfolded).max(axis=1) > 0  # the pairs the fold changes (D_y < 0): about half
        gaps, scales = [], []
        for path in files:
            nbrdf = keras_nbrdf(read_keras_nbrdf(path))
            value = nbrdf.mapped(folded[moved])
            gaps.append(np.median(np.abs(value - nbrdf.mapped(unfolded[moved]))))
            scales.append(np.median(np.abs(value)))
        print(f"published fits ({len(files)}), the {moved.sum()} pairs the fold changes: median |Δ ln(1 + f)| "
              f"between folded and unfolded D: median over fits {np.median(gaps):.2e}, worst {np.max(gaps):.2e} "
              f"(the values themselves: median |ln(1 + f)| {np.median(scales):.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
