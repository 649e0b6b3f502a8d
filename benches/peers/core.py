"""Peer comparisons for the native core, measured side by side in one run.

    pip install -e ".[bench]" && python benches/peers/core.py [--quick] [--json results.json]

1. MERL read: ``frenbrdf.read_merl`` against ``numpy.fromfile`` of the same bytes
   (goal: within 2× of numpy's time).
2. kNN Gaussian interpolation, N = 1,458,000 unit-vector sources (a MERL table's sample
   count), M = 1,000,000 targets, k = 8, C = 3: the whole job (tree build, query,
   weights, gather) against scipy's cKDTree (``workers=-1``) and pykdtree, each
   followed by the same numpy weighting (goal: ≥ 2× the throughput of both), and tree
   build against pykdtree's (goal: no slower).

Every contender's result is checked against a float64 reference before it is timed.
Times are the median of several repetitions, after a warm-up run.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

import frenbrdf
from frenbrdf.io.atomic import save_json

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]  # its folder, benches/
from common import gaussian_weighting, median_seconds, unit_vectors  # noqa: E402


def bench_merl_read(repeats: int) -> dict:
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "material.binary"
        frenbrdf.write_merl(path, rng.uniform(0, 1, size=(3, 90, 90, 180)))

        def numpy_read():
            return np.fromfile(path, dtype="<f8", offset=12)

        reference = numpy_read().reshape(3, 90, 90, 180) * np.array([1 / 1500, 1.15 / 1500, 1.66 / 1500])[:, None, None, None]
        np.testing.assert_array_equal(frenbrdf.read_merl(path), reference)

        ours = median_seconds(lambda: frenbrdf.read_merl(path), repeats)
        peer = median_seconds(numpy_read, repeats)
    return {"frenbrdf.read_merl_s": ours, "numpy.fromfile_s": peer, "ratio_time_ours_over_numpy": ours / peer}


def bench_knn(n: int, m: int, k: int, sigma: float, repeats: int) -> dict:
    from pykdtree.kdtree import KDTree
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(1)
    src, dst = unit_vectors(rng, n), unit_vectors(rng, m)
    values = rng.uniform(size=(n, 3))

    def ours():
        return frenbrdf.KnnInterpolator(src, dst, k, sigma).apply(values)

    def scipy_knn():
        distances, indices = cKDTree(src).query(dst, k=k, workers=-1)
        return gaussian_weighting(distances**2, indices, values, sigma)

    def pykdtree_knn():
        squared, indices = KDTree(src).query(dst, k=k, sqr_dists=True)
        return gaussian_weighting(squared.astype(np.float64), indices.astype(np.int64), values, sigma)

    # Check all three against a float64 brute-force reference on a sample of targets.
    sample = rng.choice(m, 200, replace=False)
    d2 = ((dst[sample, None, :] - src[None, :, :]) ** 2).sum(-1)
    nearest = np.argsort(d2, axis=1)[:, :k]
    reference = gaussian_weighting(np.take_along_axis(d2, nearest, axis=1), nearest, values, sigma)
    for name, function in [("frenbrdf", ours), ("scipy", scipy_knn), ("pykdtree", pykdtree_knn)]:
        np.testing.assert_allclose(function()[sample], reference, rtol=1e-9, err_msg=name)

    no_targets = np.zeros((0, 3))
    results = {
        "n_src": n, "n_dst": m, "k": k, "threads": frenbrdf._native.num_threads(),
        "frenbrdf_total_s": median_seconds(ours, repeats),
        "scipy_ckdtree_total_s": median_seconds(scipy_knn, repeats),
        "pykdtree_total_s": median_seconds(pykdtree_knn, repeats),
        "frenbrdf_build_s": median_seconds(lambda: frenbrdf.KnnInterpolator(src, no_targets, k, sigma), repeats),
        "pykdtree_build_s": median_seconds(lambda: KDTree(src), repeats),
        "scipy_ckdtree_build_s": median_seconds(lambda: cKDTree(src), repeats),
    }
    results["throughput_ratio_vs_scipy"] = results["scipy_ckdtree_total_s"] / results["frenbrdf_total_s"]
    results["throughput_ratio_vs_pykdtree"] = results["pykdtree_total_s"] / results["frenbrdf_total_s"]
    results["build_ratio_vs_pykdtree"] = results["pykdtree_build_s"] / results["frenbrdf_build_s"]
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="smaller kNN problem and fewer repeats")
    parser.add_argument("--json", type=Path, help="also write the results here")
    args = parser.parse_args()
    repeats = 3 if args.quick else 7

    print(f"threads: frenbrdf {frenbrdf._native.num_threads()}, cores {os.cpu_count()}")
    merl = bench_merl_read(repeats)
    print(f"\nMERL read (34,992,012 bytes), median of {repeats}:")
    print(f"  frenbrdf.read_merl  {merl['frenbrdf.read_merl_s'] * 1e3:8.2f} ms")
    print(f"  numpy.fromfile      {merl['numpy.fromfile_s'] * 1e3:8.2f} ms")
    print(f"  ratio ours/numpy    {merl['ratio_time_ours_over_numpy']:8.2f}×   (goal ≤ 2)")

    n, m = (200_000, 100_000) if args.quick else (1_458_000, 1_000_000)
    knn = bench_knn(n, m, k=8, sigma=0.01, repeats=max(1, repeats // 2))
    print(f"\nkNN interpolation N={n:,} M={m:,} k=8 C=3 (build + query + weights + gather):")
    for label, key in [("frenbrdf", "frenbrdf_total_s"), ("scipy cKDTree", "scipy_ckdtree_total_s"), ("pykdtree", "pykdtree_total_s")]:
        print(f"  {label:<14} {knn[key]:7.3f} s   {m / knn[key] / 1e6:6.2f} M targets/s")
    print(f"  throughput ratio vs scipy     {knn['throughput_ratio_vs_scipy']:5.2f}×   (goal ≥ 2)")
    print(f"  throughput ratio vs pykdtree  {knn['throughput_ratio_vs_pykdtree']:5.2f}×   (goal ≥ 2)")
    print("tree build:")
    for label, key in [("frenbrdf", "frenbrdf_build_s"), ("pykdtree", "pykdtree_build_s"), ("scipy cKDTree", "scipy_ckdtree_build_s")]:
        print(f"  {label:<14} {knn[key]:7.3f} s")
    print(f"  build speed ratio vs pykdtree {knn['build_ratio_vs_pykdtree']:5.2f}×   (goal ≥ 1)")

    if args.json:
        save_json(args.json, {"merl_read": merl, "knn": knn})


if __name__ == "__main__":
    main()
