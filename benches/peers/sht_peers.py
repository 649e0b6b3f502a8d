"""Spherical harmonic transform: frenbrdf.numerics.sht against peer CPU libraries, in one run.

    apt-get install -y libfftw3-dev                  # shtns builds against fftw3 (+ fftw3_omp)
    pip install -e . ducc0 shtns matplotlib
    pip install --no-deps torch-harmonics            # 0.9.x pins torch<2.15 and would downgrade it
    python benches/peers/sht_peers.py [--quick] [--workload-only] [--out bench-results/sht]

Peers (each optional: one that will not import is skipped with the reason printed):
shtns (``shtns.sht`` + ``set_grid``, float64 only on CPU; its Python interface takes one map
per call and holds the GIL, so a batch is a loop with shtns's own OpenMP threads inside each
transform), ducc0 (``ducc0.sht.experimental.analysis_2d``, geometries "GL" and "CC"; one map
per call, but it releases the GIL, so a batch is split over a pool of single-threaded
transforms, one Python thread per core) and torch-harmonics (``RealSHT`` /
``InverseRealSHT``, ``norm="ortho"``, batched natively, on the CPU).

1. The project's workload: 192 maps (3 channels x 64 slices), Gauss-Legendre grid
   90 x 180, lmax 89. Forward analysis throughput (maps/s) at 1 and 2 threads, float64
   and float32, and the throughput ratio ours/peer at the same thread count and dtype.
2. Analysis time per map on Gauss-Legendre grids 90x180, 128x256, 256x512 and
   512x1024 (lmax = nlat - 1), batch 1 and 192 (batch 8 at 512x1024, to bound time and
   memory), at each thread count (--quick: the highest only, and no 512x1024).
3. Before a configuration is timed, the library is checked on it against a float64
   reference: random band-limited coefficients a_lm (ducc0's convention: orthonormal,
   Condon-Shortley phase, f = sum_l a_l0 Y_l0 + 2 Re sum_{m>0} a_lm Y_lm) are
   synthesised in float64 by ducc0 (by shtns when ducc0 is missing); the library's
   analysis of that map, converted to a complex [l, m] array, must give back a_lm, and
   its synthesis of a_lm must give back the map. Errors are max |difference| / max
   |reference| (relative to the largest coefficient or map value). A configuration that
   fails is reported and not timed.

Every library runs in its own subprocess per thread count, with RAYON_NUM_THREADS,
OMP_NUM_THREADS (and MKL/OpenBLAS) set before import; ducc0 and shtns also get the count
as an argument, torch through ``torch.set_num_threads``. OMP_WAIT_POLICY is passed through
as it is (recorded in the results): on a machine that is busy with other work, OpenMP's
default wait policy can stall shtns for ~16 ms per call at 2 threads, and ``active`` avoids
that. Times are medians of samples of back-to-back calls (each at least 20 ms), after a
warm-up run; the report warns when other processes used more than 10% of the machine's CPU
while a library was measured (from /proc/stat, less this script's own CPU time).
This file plans the runs and measures (main process and workers); the grids, the
libraries and the reference check are in sht_setup.py, the tables and charts in
sht_report.py. Results go to --out: sht_peers.md, sht_peers.json,
sht_timings.csv, sht_errors.csv, sht_time_vs_lmax.png and sht_error_vs_lmax.png (chart 1 of
research/figures: ``python benches/peers/sht_peers.py --out research/figures/sht``).
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
import traceback
from functools import partial
from pathlib import Path

import numpy as np

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]  # its folder, benches/
from sht_report import build_markdown, save_report  # noqa: E402
from sht_setup import (  # noqa: E402
    BIG_BATCH,
    BIG_NLAT,
    BUSY_SHARE,
    CHECK_BATCH,
    EQUIANGULAR_CHECK,
    GL_SIZES,
    LIBRARIES,
    LIBRARY_CLASSES,
    MIN_SAMPLE_S,
    TOLERANCE,
    WORKLOAD,
    check_plan,
    random_alm,
    reference_maps,
)

from common import THREAD_ENV, CpuMeter, run_metadata, time_calls  # noqa: E402


def log(message: str) -> None:
    print(message, flush=True)


# ---------------------------------------------------------------------------------------
# Worker (a subprocess): one library at one thread count.


def worker(args) -> None:
    """One library at one thread count: check each configuration against the reference, then time it."""
    spec = json.loads(Path(args.spec).read_text())
    name, threads = spec["library"], spec["threads"]
    result = {"library": name, "threads": threads, "available": False, "checks": [], "timings": [], "notes": []}
    try:
        library = LIBRARY_CLASSES[name](threads)
        result.update(available=True, version=library.version(), info=library.info())
    except Exception as error:  # noqa: BLE001 - any import failure means "skip this peer"
        result["reason"] = f"{type(error).__name__}: {error}"
        Path(args.result).write_text(json.dumps(result, indent=2))
        return
    for dtype in ("float64", "float32"):
        if dtype not in library.dtypes:
            result["notes"].append(library.dtype_note)
    references = np.load(spec["references"])
    rng = np.random.default_rng(7)
    for config in spec["configs"]:
        nlat, nlon, lmax, grid = config["nlat"], config["nlon"], config["lmax"], config["grid"]
        for dtype in library.dtypes:
            label = f"{name} {dtype} {grid} {nlat}x{nlon} lmax {lmax} threads {threads}"
            base = {"library": name, "dtype": dtype, "grid": grid, "nlat": nlat, "nlon": nlon, "lmax": lmax, "threads": threads}
            try:
                start = time.perf_counter()
                plan = library.plan(nlat, nlon, lmax, grid, dtype)
                setup_s = time.perf_counter() - start
                key = f"{grid}_{nlat}_{nlon}_{lmax}"
                if f"{key}_alm" in references.files:
                    check = check_plan(plan, {"alm": references[f"{key}_alm"], "maps": references[f"{key}_maps"]}, dtype)
                else:
                    check = {"ok": True, "unchecked": "no float64 reference library available"}
                result["checks"].append({**base, **check, "setup_s": setup_s})
                status = "ok" if check["ok"] else "FAILED"
                errors = f"analysis {check.get('analysis_err', float('nan')):.2e}, synthesis {check.get('synthesis_err', float('nan')):.2e}"
                log(f"  check {label}: {status} ({errors}){'  ' + check['hint'] if 'hint' in check else ''}")
                if not check["ok"]:
                    continue
                for batch in config["batches"]:
                    maps = rng.normal(size=(batch, nlat, nlon))
                    prepared = plan.prepare(maps)
                    # Each sample is at least MIN_SAMPLE_S of back-to-back calls: one-call samples of
                    # single 256 x 512 maps at 2 threads timed 0.72 ms in one run, 0.42 in the next.
                    timing = time_calls(partial(plan.analysis, prepared), spec["repeats"], min_sample_s=MIN_SAMPLE_S,
                                        budget_s=spec["budget_s"])
                    seconds, repeats = timing.median_s, len(timing.samples_s)
                    timing = {**base, "batch": batch, "seconds": seconds, "per_map_s": seconds / batch, "maps_per_s": batch / seconds, "repeats": repeats}
                    result["timings"].append(timing)
                    log(f"  time  {label} batch {batch}: {seconds * 1e3:9.3f} ms  {batch / seconds:9.1f} maps/s  (median of {repeats})")
                    del maps, prepared
                del plan
            except Exception as error:  # noqa: BLE001 - report and go on with the next one
                message = f"{type(error).__name__}: {error}"
                result["checks"].append({**base, "ok": False, "error": message})
                log(f"  error {label}: {message}")
                traceback.print_exc()
        Path(args.result).write_text(json.dumps(result, indent=2))  # partial results survive a crash
    Path(args.result).write_text(json.dumps(result, indent=2))

# ---------------------------------------------------------------------------------------
# Main: plan the runs, build references, run the workers, report.




def run_worker(library: str, threads: int, configs: list, references: Path, folder: Path, repeats: int, budget_s: float, timeout_s: float) -> dict:
    spec_path = folder / f"spec_{library}_{threads}.json"
    result_path = folder / f"result_{library}_{threads}.json"
    spec_path.write_text(json.dumps({"library": library, "threads": threads, "configs": configs, "references": str(references), "repeats": repeats, "budget_s": budget_s}))
    env = dict(os.environ)
    for variable in THREAD_ENV:
        env[variable] = str(threads)
    command = [sys.executable, str(Path(__file__).resolve()), "--worker", "--spec", str(spec_path), "--result", str(result_path)]
    meter = CpuMeter()  # how much of the machine other processes use while the worker runs
    try:
        completed = subprocess.run(command, env=env, timeout=timeout_s)
        returncode = completed.returncode
    except subprocess.TimeoutExpired:
        returncode = "timeout"
    wall, background = meter.read()
    if result_path.exists():
        result = json.loads(result_path.read_text())
    else:
        result = {"library": library, "threads": threads, "available": False, "checks": [], "timings": [], "notes": []}
        result["reason"] = f"worker exited with {returncode} before writing results"
    if returncode != 0:
        result.setdefault("notes", []).append(f"worker exited with {returncode} (threads {threads})")
    result["background_cpu"] = background
    result["wall_s"] = wall
    if background is not None and background > BUSY_SHARE:
        log(f"  note: other processes used {background:.0%} of the machine's CPU while this ran")
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats, no 512x1024")
    parser.add_argument("--out", type=Path, default=Path("bench-results/sht"), help="output folder (default: bench-results/sht)")
    parser.add_argument("--threads", default=None, help="comma-separated thread counts for the workload (default: 1 and all cores)")
    parser.add_argument("--size-threads", default=None, help="comma-separated thread counts for the size sweep (default: all workload counts; --quick: the highest)")
    parser.add_argument("--workload-only", action="store_true", help="only the 192-map 90x180 workload: no size sweep, no equiangular check")
    parser.add_argument("--libraries", default=",".join(LIBRARIES), help=f"comma-separated subset of {','.join(LIBRARIES)}")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--spec", help=argparse.SUPPRESS)
    parser.add_argument("--result", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args)
        return

    started = time.perf_counter()
    run = run_metadata()
    cores = os.cpu_count() or 1
    threads_list = sorted({int(t) for t in args.threads.split(",")}) if args.threads else sorted({1, cores})
    if args.workload_only:
        size_threads = []
    elif args.size_threads:
        size_threads = sorted({int(t) for t in args.size_threads.split(",")})
        threads_list = sorted(set(threads_list) | set(size_threads))
    else:
        size_threads = threads_list[-1:] if args.quick else threads_list
    libraries = [name for name in args.libraries.split(",") if name]
    unknown = set(libraries) - set(LIBRARIES)
    if unknown:
        parser.error(f"unknown libraries: {', '.join(sorted(unknown))}")
    repeats, budget_s = (3, 1.0) if args.quick else (7, 3.0)
    sizes = [s for s in GL_SIZES if not (args.quick and s[0] == BIG_NLAT)]

    def gl(nlat, nlon, batches):
        return {"grid": "gauss", "nlat": nlat, "nlon": nlon, "lmax": nlat - 1, "batches": batches}

    workload_config = gl(WORKLOAD["nlat"], WORKLOAD["nlon"], [WORKLOAD["batch"]])
    size_configs = [gl(nlat, nlon, [1, BIG_BATCH if nlat == BIG_NLAT else 192]) for nlat, nlon in sizes]
    check_configs = size_configs + [{**EQUIANGULAR_CHECK, "batches": []}] if size_threads else [workload_config]

    load_before = [round(x, 2) for x in os.getloadavg()]
    log(f"cores {cores}, workload threads {threads_list}, size sweep threads {size_threads or 'none'}, load average {load_before}")
    if args.quick:
        log(f"quick mode: up to {repeats} repeats, {BIG_NLAT}x{2 * BIG_NLAT} skipped")

    with tempfile.TemporaryDirectory(prefix="sht_peers_") as folder:
        folder = Path(folder)
        rng = np.random.default_rng(2025)
        arrays, reference = {}, "none"
        for config in check_configs:
            nlat, nlon, lmax, grid = config["nlat"], config["nlon"], config["lmax"], config["grid"]
            alm = random_alm(rng, CHECK_BATCH, lmax)
            try:
                maps, reference = reference_maps(alm, nlat, nlon, lmax, grid)
            except ImportError:
                log("no reference library (ducc0 or shtns): results will be timed unchecked")
                break
            arrays[f"{grid}_{nlat}_{nlon}_{lmax}_alm"] = alm
            arrays[f"{grid}_{nlat}_{nlon}_{lmax}_maps"] = maps
        references = folder / "references.npz"
        np.savez(references, **arrays)
        log(f"float64 reference: {reference}")

        results = []
        for threads in threads_list:
            for library in libraries:
                if threads in size_threads:
                    # The workload is the 90x180 batch-192 size row: time it there once.
                    configs = [dict(c) for c in check_configs]
                else:
                    configs = [workload_config]
                log(f"\n[{library}, {threads} thread{'s' if threads > 1 else ''}]")
                results.append(run_worker(library, threads, configs, references, folder, repeats, budget_s, timeout_s=1800))

    libraries_info = {}
    for result in results:
        info = libraries_info.setdefault(result["library"], {"available": result["available"], "notes": []})
        for field in ("version", "reason", "info"):
            if field in result:
                info[field] = result[field]
        info["available"] = info["available"] and result["available"]
        info["notes"] += result.get("notes", [])
        if not result["available"]:
            log(f"skipped {result['library']} ({result['threads']} threads): {result.get('reason')}")
    data = {
        "meta": {
            "cores": cores, "platform": platform.platform(), "python": platform.python_version(), "numpy": np.__version__,
            "threads": threads_list, "size_threads": size_threads, "quick": args.quick, "repeats": repeats,
            "reference": reference, "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY"), "load_before": load_before, "load_after": [round(x, 2) for x in os.getloadavg()],
            "tolerance": TOLERANCE, "workload": WORKLOAD, "run": run,
        },
        "libraries": libraries_info,
        "workers": [{"library": r["library"], "threads": r["threads"], "wall_s": round(r["wall_s"], 2),
                     "background_cpu": None if r["background_cpu"] is None else round(r["background_cpu"], 3)} for r in results],
        "checks": [c for r in results for c in r["checks"]],
        "timings": [t for r in results for t in r["timings"]],
    }
    markdown = build_markdown(data)
    data["meta"]["elapsed_s"] = round(time.perf_counter() - started, 1)
    charts = save_report(data, markdown, args.out)
    print("\n" + markdown)
    log(f"wrote {args.out / 'sht_peers.md'}, {args.out / 'sht_peers.json'}, " + ", ".join(str(args.out / c) if c.endswith(".png") else c for c in charts))
    worst = max((r["background_cpu"] or 0 for r in results), default=0)
    if worst > BUSY_SHARE:
        log(f"warning: other processes used up to {worst:.0%} of the machine's CPU during the run: timings are unreliable (see sht_peers.md)")
    log(f"elapsed {data['meta']['elapsed_s']} s")


if __name__ == "__main__":
    main()
