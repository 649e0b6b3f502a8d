"""kNN Gaussian interpolation over heavily clustered sources: frenbrdf against scipy's cKDTree.

    python benches/peers/knn_clustered.py [--queries 1000000] [--scipy-timeout 120] [--copies 8]
                                    [--query-domain sphere|hemisphere] [--out bench-results/knn]

The frequency-loss truth interpolates the bins of a MERL θ_h slice, seen as directions
(θ_d, φ_d) with their reciprocal copies φ_d + π, onto an SHT grid. Those 90 × 360
directions are far from uniform: 360 of them are exactly the pole, and the rings around
it hold 360 points each only 3·10⁻⁴ apart. scipy's cKDTree was reported to need over
10 minutes for 10⁶ queries on such a set, against 2 s on uniform points. Source sets:

- ``merl-slice``: those 32,400 directions (upper hemisphere);
- ``merl-slice×C``: every one of them C times (``--copies``), the copies jittered by 10⁻⁹,
  as directions measured again and again with rounding noise;
- ``uniform-hemisphere`` and ``uniform-sphere``: uniform points of the same counts, on
  the clustered sets' own hemisphere and on the whole sphere.

Queries are uniform on the whole sphere (the SHT grid covers it; the truth's ``"zero"``
extension queries the lower half, far from every source) or, with ``--query-domain
hemisphere``, on the upper hemisphere only.

Both contenders compute the same thing: tree build, the k nearest sources of every query,
Gaussian weights relative to the nearest (FreNBRDF Eq. 5–7) and the weighted mean of three
channels. Ours is ``KnnInterpolator(src, dst, k, σ).apply(values)``; scipy's is
``cKDTree(src).query(dst, k, workers=threads)`` followed by the same weighting in numpy.
Both are checked against a float64 brute-force reference on a subset of the queries
before anything is timed. scipy runs in a subprocess, killed once a timed run takes more
than ``--scipy-timeout`` seconds, and is reported as "> timeout".

Threads: frenbrdf uses ``RAYON_NUM_THREADS`` (all cores when unset) and scipy the same
number of workers; for single-threaded numbers run with ``RAYON_NUM_THREADS=1
OMP_NUM_THREADS=1``. Writes ``knn_clustered.md`` and ``knn_clustered.json`` to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import frenbrdf
from frenbrdf.io.atomic import save_json, write_text

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]  # its folder, benches/
from common import CpuMeter, gaussian_weighting, time_calls, unit_vectors  # noqa: E402

CHANNELS = 3
JITTER = 1e-9


# ---------------------------------------------------------------------------------------
# Point sets


def merl_slice_directions() -> np.ndarray:
    """The bins of one θ_h slice as directions (θ_d, φ_d) and (θ_d, φ_d + π): ``(32400, 3)``."""
    _, theta_d, phi_d = frenbrdf.merl_bin_angles()
    theta, phi = np.meshgrid(theta_d, np.concatenate([phi_d, phi_d + np.pi]), indexing="ij")
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1).reshape(-1, 3)


def source_sets(copies: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Each clustered set followed by uniform points of the same count."""
    grid = merl_slice_directions()
    clustered = {"merl-slice": grid}
    if copies > 1:
        repeated = np.repeat(grid, copies, axis=0) + rng.normal(scale=JITTER, size=(copies * len(grid), 3))
        clustered[f"merl-slice×{copies}"] = repeated / np.linalg.norm(repeated, axis=1, keepdims=True)
    sets = {}
    for name, points in clustered.items():
        sets[name] = points
        sets[f"uniform-hemisphere, {len(points):,}"] = unit_vectors(rng, len(points), hemisphere=True)
        sets[f"uniform-sphere, {len(points):,}"] = unit_vectors(rng, len(points))
    return sets


def smooth_values(points: np.ndarray) -> np.ndarray:
    """Three channels, a smooth function of position: equally near duplicates carry (nearly)
    the same value, so any choice among them gives the same interpolated result."""
    x, y, z = points.T
    return np.stack([x + 2 * y, np.exp(z) * x, np.cos(3 * y)], axis=-1)


# ---------------------------------------------------------------------------------------
# The computation, three ways


def brute_force(src: np.ndarray, values: np.ndarray, dst: np.ndarray, k: int, sigma: float):
    """float64 reference: sorted squared distances of the k nearest ``(m, k)`` and the result ``(m, C)``."""
    squared, indices = [], []
    for chunk in np.array_split(dst, max(1, len(dst) // 8)):
        d2 = ((chunk[:, None, :] - src[None, :, :]) ** 2).sum(-1)
        part = np.argpartition(d2, k - 1, axis=1)[:, :k]
        order = np.argsort(np.take_along_axis(d2, part, axis=1), axis=1, kind="stable")
        part = np.take_along_axis(part, order, axis=1)
        squared.append(np.take_along_axis(d2, part, axis=1))
        indices.append(part)
    squared, indices = np.concatenate(squared), np.concatenate(indices)
    return squared, gaussian_weighting(squared, indices, values, sigma)


def check(name: str, squared_found: np.ndarray, result: np.ndarray, reference) -> None:
    """Same neighbour distances as brute force (ties among duplicates may name other, equally
    near, points) and the same interpolated values (up to the 10⁻⁹ jitter of near-duplicates)."""
    squared, expected = reference
    np.testing.assert_allclose(np.sort(squared_found, axis=1), squared, rtol=1e-12, atol=1e-30, err_msg=name)
    np.testing.assert_allclose(result, expected, rtol=1e-7, atol=1e-8, err_msg=name)


def ours(src, dst, values, k, sigma):
    op = frenbrdf.KnnInterpolator(src, dst, k, sigma)
    return op, op.apply(values)


def scipy_knn(src, dst, values, k, sigma, workers):
    from scipy.spatial import cKDTree

    start = time.perf_counter()
    tree = cKDTree(src)
    built = time.perf_counter()
    distances, indices = tree.query(dst, k=k, workers=workers)
    queried = time.perf_counter()
    distances, indices = distances.reshape(len(dst), k), indices.reshape(len(dst), k)
    result = gaussian_weighting(distances**2, indices, values, sigma)
    done = time.perf_counter()
    return indices, result, {"build_s": built - start, "query_s": queried - built, "weighting_s": done - queried}


def scipy_worker(spec_path: Path) -> None:
    """Runs in a subprocess: check scipy on the check subset, say so, then time the whole job."""
    spec = json.loads(spec_path.read_text())
    folder = Path(spec["folder"])
    src, dst, values = (np.load(folder / f"{name}.npy") for name in ("src", "dst", "values"))
    check_rows = np.load(folder / "check_rows.npy")
    reference = np.load(folder / "reference_squared.npy"), np.load(folder / "reference_result.npy")
    k, sigma, workers = spec["k"], spec["sigma"], spec["workers"]
    indices, result, _ = scipy_knn(src, dst[check_rows], values, k, sigma, workers)
    squared = ((dst[check_rows][:, None, :] - src[indices]) ** 2).sum(-1)
    check("scipy", squared, result, reference)
    print("checked", flush=True)
    times = []
    for _ in range(spec["repeats"]):
        start = time.perf_counter()
        _, _, parts = scipy_knn(src, dst, values, k, sigma, workers)
        times.append({"total_s": time.perf_counter() - start, **parts})
    best = min(times, key=lambda t: t["total_s"])
    Path(spec["result"]).write_text(json.dumps(best))


def run_scipy(folder: Path, k: int, sigma: float, workers: int, repeats: int, timeout_s: float) -> dict:
    """scipy in a subprocess; the timeout starts once its check has passed."""
    result_path = folder / "scipy_result.json"
    result_path.unlink(missing_ok=True)
    spec_path = folder / "scipy_spec.json"
    spec_path.write_text(json.dumps({"folder": str(folder), "k": k, "sigma": sigma, "workers": workers,
                                     "repeats": repeats, "result": str(result_path)}))
    process = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker", str(spec_path)],
                               stdout=subprocess.PIPE, text=True)
    first_line = process.stdout.readline().strip()
    if first_line != "checked":
        process.wait()
        raise RuntimeError(f"the scipy worker failed its check against brute force or crashed "
                           f"(exit code {process.returncode}; its error is above)")
    try:
        process.wait(timeout=timeout_s * repeats)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
        return {"timed_out": True, "timeout_s": timeout_s}
    if process.returncode != 0:
        raise RuntimeError(f"the scipy worker exited with {process.returncode}")
    return {"timed_out": False, **json.loads(result_path.read_text())}


# ---------------------------------------------------------------------------------------
# Main


def bench_set(name: str, src: np.ndarray, dst: np.ndarray, args, threads: int, rng) -> dict:
    values = smooth_values(src)
    check_rows = np.sort(rng.choice(len(dst), min(args.check, len(dst)), replace=False))
    reference = brute_force(src, values, dst[check_rows], args.k, args.sigma)

    op, result = ours(src, dst[check_rows], values, args.k, args.sigma)
    squared = ((dst[check_rows][:, None, :] - src[op.indices]) ** 2).sum(-1)
    check("frenbrdf", squared, result, reference)

    timing = time_calls(lambda: ours(src, dst, values, args.k, args.sigma), args.repeats, warmup=False)
    row = {"source_set": name, "n_src": len(src), "n_dst": len(dst), "frenbrdf_s": timing.best_s}

    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for file, array in [("src", src), ("dst", dst), ("values", values), ("check_rows", check_rows),
                            ("reference_squared", reference[0]), ("reference_result", reference[1])]:
            np.save(folder / f"{file}.npy", array)
        scipy = run_scipy(folder, args.k, args.sigma, threads, args.repeats, args.scipy_timeout)
    row["scipy_timed_out"] = scipy.pop("timed_out")
    if row["scipy_timed_out"]:
        row["scipy_s"] = None
    else:
        row["scipy_s"] = scipy["total_s"]
        row["scipy_parts_s"] = {key: scipy[key] for key in ("build_s", "query_s", "weighting_s")}
    return row


def markdown(rows: list[dict], meta: dict) -> str:
    lines = [
        f"kNN Gaussian interpolation, k = {meta['k']}, σ = {meta['sigma']}, C = 3: "
        f"tree build + query + weights + gather, {meta['n_queries']:,} queries uniform on the "
        f"{meta['query_domain']}; {meta['threads']} thread(s) ({meta['cpu_count']} cores), best of "
        f"{meta['repeats']}. Both checked against float64 brute force on {meta['check']} queries first.",
        "",
        "| source set | sources | frenbrdf (s) | scipy cKDTree (s) | scipy / frenbrdf |",
        "|---|---:|---:|---:|---:|",
    ]
    for row in rows:
        if row["scipy_timed_out"]:
            timeout = meta["scipy_timeout_s"]
            scipy, ratio = f"> {timeout:g}", f"> {timeout / row['frenbrdf_s']:.1f}×"
        else:
            scipy, ratio = f"{row['scipy_s']:.2f}", f"{row['scipy_s'] / row['frenbrdf_s']:.1f}×"
        lines.append(f"| {row['source_set']} | {row['n_src']:,} | {row['frenbrdf_s']:.2f} | {scipy} | {ratio} |")
    if meta.get("background_cpu") is not None:
        lines += ["", f"Other processes used {meta['background_cpu']:.0%} of the machine's CPU during the run."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--queries", type=float, default=1e6, help="number of query points (default 1e6)")
    parser.add_argument("--scipy-timeout", type=float, default=120.0,
                        help="seconds per timed run before scipy is killed (default 120)")
    parser.add_argument("--copies", type=int, default=8,
                        help="copies of each bin in the merl-slice×C set (default 8; 1: no such set)")
    parser.add_argument("--query-domain", choices=("sphere", "hemisphere"), default="sphere")
    parser.add_argument("--k", type=int, default=8)
    parser.add_argument("--sigma", type=float, default=0.01)
    parser.add_argument("--repeats", type=int, default=1, help="timed runs per contender; the best is reported")
    parser.add_argument("--check", type=int, default=200, help="queries checked against brute force (default 200)")
    parser.add_argument("--out", type=Path, default=Path("bench-results/knn"))
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker is not None:
        scipy_worker(args.worker)
        return

    import scipy

    threads = frenbrdf._native.num_threads()
    rng = np.random.default_rng(0)
    dst = unit_vectors(rng, int(args.queries), hemisphere=args.query_domain == "hemisphere")
    meta = {"k": args.k, "sigma": args.sigma, "n_queries": len(dst), "query_domain": args.query_domain,
            "threads": threads, "cpu_count": os.cpu_count(), "repeats": args.repeats, "check": args.check,
            "scipy_timeout_s": args.scipy_timeout, "copies": args.copies, "jitter": JITTER,
            "versions": {"frenbrdf": frenbrdf.__version__, "numpy": np.__version__, "scipy": scipy.__version__,
                         "python": platform.python_version()}}
    print(f"{len(dst):,} queries on the {args.query_domain}, k = {args.k}, {threads} thread(s)", flush=True)
    meter = CpuMeter()
    rows = []
    for name, src in source_sets(args.copies, rng).items():
        row = bench_set(name, src, dst, args, threads, rng)
        scipy_text = f"> {args.scipy_timeout:g} s (killed)" if row["scipy_timed_out"] else f"{row['scipy_s']:.2f} s"
        print(f"  {name:<28} {len(src):>9,} sources   frenbrdf {row['frenbrdf_s']:7.2f} s   scipy {scipy_text}",
              flush=True)
        rows.append(row)
    _, background = meter.read()
    if background is not None:
        meta["background_cpu"] = background

    args.out.mkdir(parents=True, exist_ok=True)
    text = markdown(rows, meta)
    write_text(args.out / "knn_clustered.md", text)
    save_json(args.out / "knn_clustered.json", {"meta": meta, "rows": rows})
    print("\n" + text)
    print(f"wrote {args.out / 'knn_clustered.md'} and {args.out / 'knn_clustered.json'}")


if __name__ == "__main__":
    main()
