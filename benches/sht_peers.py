"""Spherical harmonic transform: frenbrdf.sht against peer CPU libraries, in one run.

    apt-get install -y libfftw3-dev                  # shtns builds against fftw3 (+ fftw3_omp)
    pip install -e . ducc0 shtns matplotlib
    pip install --no-deps torch-harmonics            # 0.9.x pins torch<2.15 and would downgrade it
    python benches/sht_peers.py [--quick] [--workload-only] [--out bench-results/sht]

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
Results go to --out: sht_peers.md, sht_peers.json,
sht_timings.csv, sht_errors.csv, sht_time_vs_lmax.png and sht_error_vs_lmax.png (chart 1 of
docs/charts: ``python benches/sht_peers.py --out docs/charts/sht``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

LIBRARIES = ("frenbrdf", "shtns", "ducc0", "torch-harmonics")
PEERS = LIBRARIES[1:]
WORKLOAD = {"grid": "gauss", "nlat": 90, "nlon": 180, "lmax": 89, "batch": 192}
GL_SIZES = [(90, 180), (128, 256), (256, 512), (512, 1024)]
BIG_NLAT = 512  # the size whose "batch 192" row runs with BIG_BATCH maps instead
BIG_BATCH = 8
# Accuracy-only row for the equiangular grid (Clenshaw-Curtis: nlat rings, both poles);
# lmax = (nlat - 1) // 2 is exact for every library's quadrature.
EQUIANGULAR_CHECK = {"grid": "equiangular", "nlat": 91, "nlon": 180, "lmax": 44}
CHECK_BATCH = 2
TOLERANCE = {"float64": 1e-9, "float32": 1e-4}
MIN_SAMPLE_S = 0.02  # shortest timed sample: short calls are repeated within one
BUSY_SHARE = 0.10  # share of all cores used by other processes above which the report warns
THREAD_ENV = ("RAYON_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


def log(message: str) -> None:
    print(message, flush=True)


def median_seconds(function, repeats: int, budget_s: float) -> tuple[float, int]:
    """Median time per call after a warm-up; fewer samples (at least 3) when one call is slow.

    Each sample times back-to-back calls lasting at least ``MIN_SAMPLE_S``: a sample of
    one sub-millisecond call is at the mercy of a single wake-up or preemption on a
    shared machine (seen here: single 256 x 512 maps at 2 threads timed 0.72 ms in one
    run, 0.42 in the next).
    """
    start = time.perf_counter()
    function()  # warm-up: caches, thread pools, allocator, lazy initialisation
    first = max(time.perf_counter() - start, 1e-9)
    calls = max(1, math.ceil(MIN_SAMPLE_S / first))
    count = max(3, min(repeats, int(budget_s / (first * calls))))
    times = []
    for _ in range(count):
        start = time.perf_counter()
        for _ in range(calls):
            function()
        times.append((time.perf_counter() - start) / calls)
    return statistics.median(times), count


# ---------------------------------------------------------------------------------------
# Coefficient layouts. The common layout is a complex array [..., l, m] (m >= 0, zero
# for m > l) in ducc0's convention; ducc0 and shtns store the same numbers as a flat
# m-major vector (the healpy order: index = m * (2 lmax + 1 - m) / 2 + l).


def healpy_indices(lmax: int) -> tuple[np.ndarray, np.ndarray]:
    ls, ms = [], []
    for m in range(lmax + 1):
        ls.extend(range(m, lmax + 1))
        ms.extend([m] * (lmax + 1 - m))
    return np.array(ls), np.array(ms)


def healpy_to_lm(flat: np.ndarray, lmax: int) -> np.ndarray:
    ls, ms = healpy_indices(lmax)
    out = np.zeros(flat.shape[:-1] + (lmax + 1, lmax + 1), dtype=np.complex128)
    out[..., ls, ms] = flat
    return out


def lm_to_healpy(alm: np.ndarray, lmax: int, dtype=np.complex128) -> np.ndarray:
    ls, ms = healpy_indices(lmax)
    return np.ascontiguousarray(alm[..., ls, ms], dtype=dtype)


def random_alm(rng: np.random.Generator, batch: int, lmax: int) -> np.ndarray:
    """Random band-limited coefficients [batch, l, m]; a_l0 real (the map is real)."""
    alm = rng.normal(size=(batch, lmax + 1, lmax + 1)) + 1j * rng.normal(size=(batch, lmax + 1, lmax + 1))
    alm[:, :, 0] = alm[:, :, 0].real
    return np.tril(alm)  # zero where m > l


# ---------------------------------------------------------------------------------------
# Libraries. Each plan takes maps (batch, nlat, nlon) and exposes:
#   prepare(maps)       -> native input in the plan's dtype (outside the timed region)
#   analysis(prepared)  -> native coefficients (this call is what is timed)
#   to_lm(native)       -> complex128 [batch, l, m] in ducc0's convention
#   synthesis_lm(alm)   -> float64 maps (batch, nlat, nlon) from complex [batch, l, m]


class Library:
    name = ""
    dtypes = ("float64", "float32")
    dtype_note = ""

    def __init__(self, threads: int):
        self.threads = threads

    def version(self) -> str:
        raise NotImplementedError

    def info(self) -> dict:
        return {}

    def plan(self, nlat: int, nlon: int, lmax: int, grid: str, dtype: str):
        raise NotImplementedError


class Frenbrdf(Library):
    name = "frenbrdf"

    def __init__(self, threads: int):
        super().__init__(threads)
        import frenbrdf
        from frenbrdf.sht import SHT  # the module may not exist yet: ImportError -> skipped

        self.frenbrdf, self.SHT = frenbrdf, SHT

    def version(self) -> str:
        return str(getattr(self.frenbrdf, "__version__", "?"))

    def info(self) -> dict:
        native = getattr(self.frenbrdf, "_native", None)
        threads = native.num_threads() if native is not None and hasattr(native, "num_threads") else None
        return {"module": self.frenbrdf.__file__, "rayon_threads": threads}

    def plan(self, nlat, nlon, lmax, grid, dtype):
        sht = self.SHT(nlat, nlon, lmax, grid=grid, dtype=dtype)
        lm = np.asarray(sht.degrees_orders())
        if lm.shape != ((lmax + 1) ** 2, 2):
            raise ValueError(f"degrees_orders() has shape {lm.shape}, expected {((lmax + 1) ** 2, 2)}")
        complex_dtype = np.complex64 if dtype == "float32" else np.complex128

        class Plan:
            def prepare(self, maps):
                maps = np.ascontiguousarray(maps, dtype=dtype)
                batch = maps.shape[0]
                if batch == 1:
                    return maps[0]  # one map: a plain (nlat, nlon) array
                # The workload's shape: channels x slices x nlat x nlon.
                return maps.reshape(3, batch // 3, nlat, nlon) if batch % 3 == 0 else maps

            def analysis(self, maps):
                return sht.analysis(maps)

            def to_lm(self, coeffs):
                alm = np.asarray(sht.to_complex(coeffs), dtype=np.complex128)
                return alm.reshape(-1, lmax + 1, lmax + 1)

            def synthesis_lm(self, alm):
                coeffs = sht.from_complex(np.ascontiguousarray(alm, dtype=complex_dtype))
                return np.asarray(sht.synthesis(coeffs), dtype=np.float64).reshape(-1, nlat, nlon)

        return Plan()


class Shtns(Library):
    name = "shtns"
    dtypes = ("float64",)
    dtype_note = "shtns transforms in float64 only on the CPU (SHT_FP32 is GPU-only)"

    def __init__(self, threads: int):
        super().__init__(threads)
        import shtns

        self.shtns = shtns

    def version(self) -> str:
        return str(getattr(self.shtns, "__version__", "?"))

    def info(self) -> dict:
        return {"build": "see the '[SHTns ...] built ... id:' banner line (SIMD, openmp)"}

    def plan(self, nlat, nlon, lmax, grid, dtype):
        shtns = self.shtns
        sh = shtns.sht(lmax, lmax, 1, shtns.sht_orthonormal, self.threads)
        # sht_gauss: Gauss grid, the fastest algorithm chosen by timing at set-up;
        # sht_reg_poles: equispaced rings including both poles (Clenshaw-Curtis).
        kind = shtns.sht_gauss if grid == "gauss" else shtns.sht_reg_poles
        sh.set_grid(nlat, nlon, kind | shtns.SHT_PHI_CONTIGUOUS)
        if tuple(sh.spat_shape) != (nlat, nlon):
            raise ValueError(f"shtns spatial shape {sh.spat_shape}, expected {(nlat, nlon)}")

        class Plan:
            def prepare(self, maps):
                maps = np.ascontiguousarray(maps, dtype=np.float64)
                return maps, np.empty((maps.shape[0], sh.nlm), dtype=np.complex128)

            def analysis(self, prepared):
                maps, out = prepared  # shtns's Python interface transforms one map per call
                for i in range(maps.shape[0]):
                    sh.spat_to_SH(maps[i], out[i])
                return out

            def to_lm(self, out):
                return healpy_to_lm(out, lmax)

            def synthesis_lm(self, alm):
                flat = lm_to_healpy(alm, lmax)
                maps = np.empty((alm.shape[0], nlat, nlon))
                for i in range(alm.shape[0]):
                    sh.SH_to_spat(flat[i], maps[i])
                return maps

        return Plan()


class Ducc0(Library):
    name = "ducc0"

    def __init__(self, threads: int):
        super().__init__(threads)
        import ducc0

        self.ducc0 = ducc0
        sht = ducc0.sht.experimental if hasattr(ducc0.sht, "experimental") else ducc0.sht
        self.analysis_2d, self.synthesis_2d = sht.analysis_2d, sht.synthesis_2d

    def version(self) -> str:
        return self.ducc0.__version__

    def info(self) -> dict:
        return {"batch_strategy": "one single-threaded transform per map, maps split over a pool of `threads` Python threads; batch 1: nthreads=threads"}

    def plan(self, nlat, nlon, lmax, grid, dtype):
        geometry = "GL" if grid == "gauss" else "CC"
        threads = self.threads
        analysis_2d, synthesis_2d = self.analysis_2d, self.synthesis_2d
        if threads > 1 and not hasattr(self, "pool"):
            from concurrent.futures import ThreadPoolExecutor

            self.pool = ThreadPoolExecutor(threads)
        pool = getattr(self, "pool", None)
        complex_dtype = np.complex64 if dtype == "float32" else np.complex128
        nalm = (lmax + 1) * (lmax + 2) // 2

        class Plan:
            def prepare(self, maps):
                maps = np.ascontiguousarray(maps, dtype=dtype)
                return maps, np.empty((maps.shape[0], 1, nalm), dtype=complex_dtype)

            def analysis(self, prepared):
                maps, out = prepared  # spin 0 takes one map per call
                batch = maps.shape[0]
                if pool is None or batch < threads:
                    for i in range(batch):
                        analysis_2d(map=maps[i : i + 1], spin=0, lmax=lmax, geometry=geometry, nthreads=threads, alm=out[i])
                    return out

                # ducc0 releases the GIL: a batch runs fastest as one contiguous chunk
                # of single-threaded transforms per thread (measured: ~2x nthreads=2
                # per map at 90 x 180 on 2 cores).
                def chunk(indices):
                    for i in indices:
                        analysis_2d(map=maps[i : i + 1], spin=0, lmax=lmax, geometry=geometry, nthreads=1, alm=out[i])

                list(pool.map(chunk, np.array_split(np.arange(batch), threads)))
                return out

            def to_lm(self, out):
                return healpy_to_lm(out[:, 0], lmax)

            def synthesis_lm(self, alm):
                flat = lm_to_healpy(alm, lmax, complex_dtype)
                maps = [
                    synthesis_2d(alm=flat[i : i + 1], spin=0, lmax=lmax, geometry=geometry, ntheta=nlat, nphi=nlon, nthreads=threads)[0]
                    for i in range(alm.shape[0])
                ]
                return np.asarray(maps, dtype=np.float64)

        return Plan()


class TorchHarmonics(Library):
    name = "torch-harmonics"

    def __init__(self, threads: int):
        super().__init__(threads)
        import torch
        import torch_harmonics

        torch.set_num_threads(threads)
        self.torch, self.th = torch, torch_harmonics
        self.cache = {}  # float64 modules per grid; float32 plans are cast copies

    def version(self) -> str:
        return f"{self.th.__version__} (torch {self.torch.__version__})"

    def info(self) -> dict:
        return {"torch_threads": self.torch.get_num_threads()}

    def modules(self, nlat, nlon, lmax, grid):
        key = (nlat, nlon, lmax, grid)
        if key not in self.cache:
            self.cache.clear()  # one grid at a time: the 512 x 1024 weights are 1 GiB each
            name = "legendre-gauss" if grid == "gauss" else "equiangular"
            # torch-harmonics' lmax / mmax count degrees: l < lmax.
            forward = self.th.RealSHT(nlat, nlon, lmax=lmax + 1, mmax=lmax + 1, grid=name, norm="ortho", csphase=True)
            inverse = self.th.InverseRealSHT(nlat, nlon, lmax=lmax + 1, mmax=lmax + 1, grid=name, norm="ortho", csphase=True)
            self.cache[key] = (forward.to(self.torch.float64), inverse.to(self.torch.float64))
        return self.cache[key]

    def plan(self, nlat, nlon, lmax, grid, dtype):
        import copy

        torch = self.torch
        forward, inverse = self.modules(nlat, nlon, lmax, grid)
        torch_dtype = getattr(torch, dtype)
        if dtype != "float64":
            forward, inverse = copy.deepcopy(forward).to(torch_dtype), copy.deepcopy(inverse).to(torch_dtype)
        complex_dtype = np.complex64 if dtype == "float32" else np.complex128

        class Plan:
            def prepare(self, maps):
                return torch.from_numpy(np.ascontiguousarray(maps, dtype=dtype))

            def analysis(self, maps):
                with torch.inference_mode():
                    return forward(maps)

            def to_lm(self, out):
                return out.numpy().astype(np.complex128)

            def synthesis_lm(self, alm):
                with torch.inference_mode():
                    maps = inverse(torch.from_numpy(np.ascontiguousarray(alm, dtype=complex_dtype)))
                return maps.numpy().astype(np.float64)

        return Plan()


LIBRARY_CLASSES = {cls.name: cls for cls in (Frenbrdf, Shtns, Ducc0, TorchHarmonics)}


# ---------------------------------------------------------------------------------------
# Reference data (main process) and checks (workers).


def reference_maps(alm: np.ndarray, nlat: int, nlon: int, lmax: int, grid: str) -> tuple[np.ndarray, str]:
    """float64 synthesis of alm [batch, l, m] with ducc0, or shtns when ducc0 is missing."""
    try:
        import ducc0

        sht = ducc0.sht.experimental if hasattr(ducc0.sht, "experimental") else ducc0.sht
        flat = lm_to_healpy(alm, lmax)
        geometry = "GL" if grid == "gauss" else "CC"
        maps = [sht.synthesis_2d(alm=flat[i : i + 1], spin=0, lmax=lmax, geometry=geometry, ntheta=nlat, nphi=nlon, nthreads=os.cpu_count())[0] for i in range(alm.shape[0])]
        return np.asarray(maps), f"ducc0 {ducc0.__version__}"
    except ImportError:
        pass

    plan = Shtns(os.cpu_count()).plan(nlat, nlon, lmax, grid, "float64")
    return plan.synthesis_lm(alm), "shtns"


def check_plan(plan, reference: dict, dtype: str) -> dict:
    alm, maps = reference["alm"], reference["maps"]
    scale_alm, scale_map = np.abs(alm).max(), np.abs(maps).max()
    got = plan.to_lm(plan.analysis(plan.prepare(maps)))
    if got.shape != alm.shape:
        raise ValueError(f"analysis gave coefficients of shape {got.shape} in [batch, l, m], expected {alm.shape}")
    result = {
        "analysis_err": float(np.abs(got - alm).max() / scale_alm),
        # Convention-blind diagnostic: a small magnitude error with a large analysis
        # error means a sign/phase or orientation convention differs.
        "magnitude_err": float(np.abs(np.abs(got) - np.abs(alm)).max() / scale_alm),
    }
    back = plan.synthesis_lm(alm)
    result["synthesis_err"] = float(np.abs(back.reshape(maps.shape) - maps).max() / scale_map)
    tolerance = TOLERANCE[dtype]
    result["tolerance"] = tolerance
    result["ok"] = bool(result["analysis_err"] <= tolerance and result["synthesis_err"] <= tolerance)
    if result["analysis_err"] > tolerance:
        result["hint"] = convention_hint(plan, alm, maps)
    return result


def convention_hint(plan, alm: np.ndarray, maps: np.ndarray) -> str:
    """Which common convention difference, if any, explains a failed analysis."""
    lmax = alm.shape[-1] - 1
    m = np.arange(lmax + 1)
    variants = {
        "latitude order flipped (south pole first)": (maps[:, ::-1], alm),
        "no Condon-Shortley phase ((-1)^m)": (maps, alm * (-1.0) ** m),
        "sine part sign flipped (complex conjugate)": (maps, np.conj(alm)),
        "longitude reversed": (np.roll(maps[:, :, ::-1], 1, axis=2), alm),
        "real (sqrt 2) instead of complex normalisation for m > 0": (maps, alm * np.where(m > 0, np.sqrt(2), 1.0)),
    }
    scale = np.abs(alm).max()
    found = []
    for label, (variant_maps, expected) in variants.items():
        try:
            got = plan.to_lm(plan.analysis(plan.prepare(np.ascontiguousarray(variant_maps))))
            if np.abs(got - expected).max() / scale < 1e-3:
                found.append(label)
        except Exception:  # noqa: BLE001 - a diagnostic only
            pass
    return "consistent with: " + "; ".join(found) if found else "no simple convention change explains it"


# ---------------------------------------------------------------------------------------
# Worker: one library at one thread count.


def worker(args) -> None:
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
                    seconds, repeats = median_seconds(lambda: plan.analysis(prepared), spec["repeats"], spec["budget_s"])
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


def busy_cpu_seconds() -> float | None:
    """Machine-wide busy CPU time (all processes), from /proc/stat; None off Linux."""
    try:
        values = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:9]]
    except (OSError, ValueError):
        return None
    idle = values[3] + values[4]  # idle + iowait
    return (sum(values) - idle) / os.sysconf("SC_CLK_TCK")


def own_cpu_seconds() -> float:
    import resource

    return sum(getattr(resource.getrusage(who), field) for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN) for field in ("ru_utime", "ru_stime"))


def run_worker(library: str, threads: int, configs: list, references: Path, folder: Path, repeats: int, budget_s: float, timeout_s: float) -> dict:
    spec_path = folder / f"spec_{library}_{threads}.json"
    result_path = folder / f"result_{library}_{threads}.json"
    spec_path.write_text(json.dumps({"library": library, "threads": threads, "configs": configs, "references": str(references), "repeats": repeats, "budget_s": budget_s}))
    env = dict(os.environ)
    for variable in THREAD_ENV:
        env[variable] = str(threads)
    command = [sys.executable, str(Path(__file__).resolve()), "--worker", "--spec", str(spec_path), "--result", str(result_path)]
    busy_before, own_before, start = busy_cpu_seconds(), own_cpu_seconds(), time.perf_counter()
    try:
        completed = subprocess.run(command, env=env, timeout=timeout_s)
        returncode = completed.returncode
    except subprocess.TimeoutExpired:
        returncode = "timeout"
    wall, busy_after = time.perf_counter() - start, busy_cpu_seconds()
    # Share of the machine's CPU time that other processes used while this worker ran.
    background = None
    if busy_before is not None and busy_after is not None:
        background = max(0.0, (busy_after - busy_before - (own_cpu_seconds() - own_before)) / (wall * (os.cpu_count() or 1)))
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


def key_of(row: dict) -> str:
    return f"{row['library']} {row['dtype']}"


def key_order(key: str) -> tuple[int, int]:
    library, dtype = key.split()
    return LIBRARIES.index(library), ("float64", "float32").index(dtype)


def fmt(value, spec: str, missing: str = "—") -> str:
    return missing if value is None else format(value, spec)


def build_markdown(data: dict) -> str:
    meta, timings, checks = data["meta"], data["timings"], data["checks"]
    threads_list = meta["threads"]
    lines = ["# Spherical harmonic transform: frenbrdf against peers", ""]
    lines.append(f"Machine: {meta['cores']} cores, {meta['platform']}; load average (1, 5, 15 min) before / after: {meta['load_before']} / {meta['load_after']}. "
                 f"Median of up to {meta['repeats']} samples after a warm-up, each at least {MIN_SAMPLE_S * 1e3:.0f} ms of back-to-back calls. Mode: {'quick' if meta['quick'] else 'full'}. "
                 f"OMP_WAIT_POLICY: {meta['omp_wait_policy'] or 'unset (OpenMP default)'}.")
    lines.append("")
    busy = {f"{r['library']} ({r['threads']} thr)": r["background_cpu"] for r in data["workers"] if (r["background_cpu"] or 0) > BUSY_SHARE}
    if busy:
        worst = max(busy.values())
        lines += [f"**Warning:** other processes used up to {worst:.0%} of the machine's CPU during this run "
                  f"({', '.join(f'{k}: {v:.0%}' for k, v in busy.items())}); those timings, multi-threaded ones above all "
                  "(OpenMP barriers in particular), are unreliable. Re-run on an idle machine.", ""]
    lines.append("| library | version | status |")
    lines.append("|---|---|---|")
    for name, info in data["libraries"].items():
        status = "used" if info["available"] else f"skipped: {info.get('reason', '?')}"
        notes = "; ".join(sorted(set(info.get("notes", []))))
        lines.append(f"| {name} | {info.get('version', '—')} | {status}{'; ' + notes if notes else ''} |")

    w = WORKLOAD
    lines += ["", f"## Workload: {w['batch']} maps (3 x 64), Gauss-Legendre {w['nlat']}x{w['nlon']}, lmax {w['lmax']}: analysis throughput (maps/s)", ""]
    lines.append("| library | dtype | " + " | ".join(f"{t} thread{'s' if t > 1 else ''}" for t in threads_list) + " |")
    lines.append("|---|---|" + "---|" * len(threads_list))

    def workload_rate(library, dtype, threads):
        for row in timings:
            if (row["library"], row["dtype"], row["threads"], row["grid"], row["nlat"], row["batch"]) == (library, dtype, threads, "gauss", w["nlat"], w["batch"]):
                return row["maps_per_s"]
        return None

    for library in LIBRARIES:
        for dtype in ("float64", "float32"):
            rates = [workload_rate(library, dtype, t) for t in threads_list]
            if any(r is not None for r in rates):
                lines.append(f"| {library} | {dtype} | " + " | ".join(fmt(r, ",.0f") for r in rates) + " |")
    has_ours = any(workload_rate("frenbrdf", d, t) for d in ("float64", "float32") for t in threads_list)
    lines += ["", "Throughput ratio ours/peer (same thread count and dtype; > 1 means frenbrdf is faster):", ""]
    ratios, ratio_rows = {}, []
    for peer in PEERS:
        for dtype in ("float64", "float32"):
            values = []
            for t in threads_list:
                ours, theirs = workload_rate("frenbrdf", dtype, t), workload_rate(peer, dtype, t)
                value = ours / theirs if ours and theirs else None
                values.append(value)
                ratios[f"ours/{peer} {dtype} {t} threads"] = value
            if any(v is not None for v in values):
                ratio_rows.append(f"| {peer} | {dtype} | " + " | ".join(fmt(v, ".2f") + ("×" if v else "") for v in values) + " |")
    if ratio_rows:
        lines.append("| peer | dtype | " + " | ".join(f"{t} thread{'s' if t > 1 else ''}" for t in threads_list) + " |")
        lines.append("|---|---|" + "---|" * len(threads_list))
        lines += ratio_rows
    else:
        lines.append("(no ratios: " + ("no peer was measured" if has_ours else "frenbrdf was not measured") + ".)")
    data["workload_ratios"] = ratios

    for size_threads in meta["size_threads"]:
        size_rows = [r for r in timings if r["threads"] == size_threads and r["grid"] == "gauss"]
        columns = sorted({key_of(r) for r in size_rows}, key=key_order)
        if not size_rows:
            continue
        lines += ["", f"## Analysis time per map (ms), Gauss-Legendre, lmax = nlat - 1, {size_threads} thread{'s' if size_threads > 1 else ''}", ""]
        if any(r["nlat"] == BIG_NLAT for r in size_rows):
            lines.append(f"The {BIG_NLAT}x{2 * BIG_NLAT} batch row uses {BIG_BATCH} maps, not 192, to keep time and memory in bounds.")
            lines.append("")
        lines.append("| grid | lmax | batch | " + " | ".join(columns) + " |")
        lines.append("|---|---|---|" + "---|" * len(columns))
        for nlat, nlon in GL_SIZES:
            for batch in sorted({r["batch"] for r in size_rows if r["nlat"] == nlat}):
                cells = []
                for column in columns:
                    match = [r for r in size_rows if r["nlat"] == nlat and r["batch"] == batch and key_of(r) == column]
                    cells.append(fmt(match[0]["per_map_s"] * 1e3 if match else None, ".3f"))
                lines.append(f"| {nlat}x{nlon} | {nlat - 1} | {batch} | " + " | ".join(cells) + " |")

    if checks:
        check_threads = max(c["threads"] for c in checks)
        rows = [c for c in checks if c["threads"] == check_threads]
        columns = sorted({key_of(c) for c in rows}, key=key_order)
        lines += ["", f"## Accuracy against the float64 reference ({meta['reference']}): analysis error / synthesis error", ""]
        lines.append("Max |difference| / max |reference|, over a batch of 2 random band-limited fields; a_lm compared as complex [l, m] "
                     "arrays in ducc0's convention (orthonormal, Condon-Shortley phase). "
                     f"Pass: both ≤ {TOLERANCE['float64']:g} (float64), ≤ {TOLERANCE['float32']:g} (float32). "
                     "Analysis error: the library's analysis of the reference map against the a_lm it was made from. "
                     "Synthesis error: the library's synthesis of those a_lm against the reference map "
                     "(zero for ducc0 float64 when ducc0 made the reference; the other libraries' synthesis errors are the cross-check of the reference).")
        lines.append("")
        lines.append("| grid | size | lmax | " + " | ".join(columns) + " |")
        lines.append("|---|---|---|" + "---|" * len(columns))
        grids = sorted({(c["grid"], c["nlat"], c["nlon"], c["lmax"]) for c in rows}, key=lambda g: (g[0] != "gauss", g[1]))
        for grid, nlat, nlon, lmax in grids:
            cells = []
            for column in columns:
                match = [c for c in rows if (c["grid"], c["nlat"], c["lmax"]) == (grid, nlat, lmax) and key_of(c) == column]
                if not match:
                    cells.append("—")
                elif "error" in match[0]:
                    cells.append("error")
                elif "analysis_err" not in match[0]:
                    cells.append("unchecked")
                else:
                    c = match[0]
                    cells.append(f"{c['analysis_err']:.1e} / {c['synthesis_err']:.1e}" + ("" if c["ok"] else " FAIL"))
            lines.append(f"| {'Gauss-Legendre' if grid == 'gauss' else 'equiangular (CC)'} | {nlat}x{nlon} | {lmax} | " + " | ".join(cells) + " |")
        failures = [c for c in checks if not c["ok"]]
        if failures:
            lines += ["", "Failed checks (not timed):", ""]
            for c in failures:
                detail = c.get("error") or f"analysis {c['analysis_err']:.2e}, synthesis {c['synthesis_err']:.2e}" + (f"; {c['hint']}" if "hint" in c else "")
                lines.append(f"- {key_of(c)} {c['grid']} {c['nlat']}x{c['nlon']} lmax {c['lmax']} ({c['threads']} thread{'s' if c['threads'] > 1 else ''}): {detail}")
    return "\n".join(lines) + "\n"


def lmax_axis(ax, values: list[int]) -> None:
    from matplotlib.ticker import NullLocator

    ax.set_xscale("log", base=2)
    ax.set_xticks(values, [str(v) for v in values])
    ax.xaxis.set_minor_locator(NullLocator())


def plot(data: dict, out: Path) -> list[str]:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as error:
        return [f"charts skipped: {error}"]
    size_threads = data["meta"]["size_threads"]
    rows = [r for r in data["timings"] if r["threads"] in size_threads and r["grid"] == "gauss"]
    styles = {"float64": "-", "float32": "--"}
    colours = dict(zip(LIBRARIES, ("C3", "C0", "C2", "C1")))
    written = []
    if not rows:
        return ["time chart skipped: no size-sweep timings"]

    fig, axes = plt.subplots(len(size_threads), 2, figsize=(11, 4.2 * len(size_threads)), sharey=True, squeeze=False)
    for row_axes, threads in zip(axes, size_threads):
        for ax, single in zip(row_axes, (True, False)):
            subset = [r for r in rows if (r["batch"] == 1) == single and r["threads"] == threads]
            for key in sorted({key_of(r) for r in subset}, key=key_order):
                points = sorted((r["lmax"], r["per_map_s"] * 1e3) for r in subset if key_of(r) == key)
                library, dtype = key.split()
                ax.plot(*zip(*points), styles[dtype], marker="o", color=colours[library], label=key)
            lmax_axis(ax, sorted({r["lmax"] for r in rows}))
            ax.set_yscale("log")
            ax.set_xlabel("lmax (Gauss-Legendre, nlat = lmax + 1, nlon = 2 nlat)")
            batch = "batch 1" if single else f"batch 192 ({BIG_BATCH} at {BIG_NLAT}x{2 * BIG_NLAT})"
            ax.set_title(f"{batch}, {threads} thread{'s' if threads > 1 else ''}")
            ax.grid(True, which="both", alpha=0.3)
        row_axes[0].set_ylabel("analysis time per map (ms)")
    axes[0][1].legend(fontsize=8)
    fig.suptitle("SHT analysis time per map vs lmax (lower is better)")
    fig.tight_layout()
    fig.savefig(out / "sht_time_vs_lmax.png", dpi=120)
    plt.close(fig)
    written.append("sht_time_vs_lmax.png")

    checks = [c for c in data["checks"] if c["grid"] == "gauss" and "analysis_err" in c]
    if checks:
        check_threads = max(c["threads"] for c in checks)
        checks = [c for c in checks if c["threads"] == check_threads]
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
        for ax, field, title in zip(axes, ("analysis_err", "synthesis_err"), ("analysis: max |â - a| / max |a|", "synthesis: max |f̂ - f| / max |f|")):
            for key in sorted({key_of(c) for c in checks}, key=key_order):
                points = sorted((c["lmax"], max(c[field], 1e-17)) for c in checks if key_of(c) == key)
                library, dtype = key.split()
                exact = field == "synthesis_err" and all(y <= 1e-17 for _, y in points)
                label = key + (" (is the reference: 0, drawn at 1e-17)" if exact else "")
                ax.plot(*zip(*points), styles[dtype], marker="o", color=colours[library], label=label)
            lmax_axis(ax, sorted({c["lmax"] for c in checks}))
            ax.set_yscale("log")
            ax.set_xlabel("lmax (Gauss-Legendre)")
            ax.set_title(title)
            ax.grid(True, which="both", alpha=0.3)
        axes[0].set_ylabel("max relative error vs float64 reference")
        axes[1].legend(fontsize=8)
        fig.suptitle(f"SHT round-trip error vs lmax (reference: {data['meta']['reference']})")
        fig.tight_layout()
        fig.savefig(out / "sht_error_vs_lmax.png", dpi=120)
        plt.close(fig)
        written.append("sht_error_vs_lmax.png")
    return written


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
            "tolerance": TOLERANCE, "workload": WORKLOAD,
        },
        "libraries": libraries_info,
        "workers": [{"library": r["library"], "threads": r["threads"], "wall_s": round(r["wall_s"], 2),
                     "background_cpu": None if r["background_cpu"] is None else round(r["background_cpu"], 3)} for r in results],
        "checks": [c for r in results for c in r["checks"]],
        "timings": [t for r in results for t in r["timings"]],
    }
    markdown = build_markdown(data)
    data["meta"]["elapsed_s"] = round(time.perf_counter() - started, 1)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "sht_peers.md").write_text(markdown)
    (args.out / "sht_peers.json").write_text(json.dumps(data, indent=2))
    from frenbrdf.atomic import save_csv

    save_csv(args.out / "sht_timings.csv", data["timings"])
    save_csv(args.out / "sht_errors.csv", data["checks"])
    charts = plot(data, args.out)
    print("\n" + markdown)
    log(f"wrote {args.out / 'sht_peers.md'}, {args.out / 'sht_peers.json'}, " + ", ".join(str(args.out / c) if c.endswith(".png") else c for c in charts))
    worst = max((r["background_cpu"] or 0 for r in results), default=0)
    if worst > BUSY_SHARE:
        log(f"warning: other processes used up to {worst:.0%} of the machine's CPU during the run: timings are unreliable (see sht_peers.md)")
    log(f"elapsed {data['meta']['elapsed_s']} s")


if __name__ == "__main__":
    main()
