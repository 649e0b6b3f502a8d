"""What the SHT peer comparison (``benches/peers/sht_peers.py``) runs: its grids, batches and
tolerances, the libraries behind one plan interface, the float64 reference and the check
of a library against it.

Imported by the main process and by every worker subprocess, where it must stay light:
numpy only at module level; each library is imported when its class is instantiated.
"""

from __future__ import annotations

import os

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
        from frenbrdf.numerics.sht import SHT  # the module may not exist yet: ImportError -> skipped

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

