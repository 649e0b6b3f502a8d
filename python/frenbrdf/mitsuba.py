"""Render MERL tables and NBRDFs in Mitsuba 3: a BSDF plugin evaluated in Dr.Jit.

:func:`register` adds a BSDF plugin named ``"frenbrdf"`` to Mitsuba, so any Mitsuba 3
scene can use a measured MERL table or a neural BRDF::

    import mitsuba as mi
    from frenbrdf import mitsuba as fm

    fm.set_variant()                     # llvm_ad_rgb, or scalar_rgb with a warning
    fm.register()
    scene = mi.load_dict({..., "shape": {"type": "sphere",
                                         "bsdf": fm.bsdf_dict("gold.binary")}})

or, without writing a scene, :func:`render_material` renders a sphere under an
environment and two directional lights.

The plugin
----------
``{"type": "frenbrdf", ...}`` takes

- ``filename``: a MERL ``.binary`` file, an NBRDF saved by
  :func:`frenbrdf.fitting.save_nbrdf`, or a published Keras NBRDF ``.h5``; or
- ``material``: a handle from :func:`material_handle` for a material held in memory (an
  :class:`frenbrdf.NBRDF`, a MERL table array): Mitsuba's properties hold only numbers,
  strings and Mitsuba objects, so Python objects travel by name (a handle keeps its
  material in memory until :func:`release_handle`);
- ``lookup`` (MERL only): ``"trilinear"`` (default) or ``"nearest"``, as in
  :func:`frenbrdf.merl_lookup`;
- ``sampling``: ``"fitted"`` (default) or ``"cosine"`` (cosine-weighted hemisphere only,
  for comparisons).

:func:`bsdf_dict` writes this dictionary for any supported material.

Conventions
-----------
Mitsuba's ``si.wi`` is the NBRDF's ``wi`` and the queried ``wo`` its ``wo`` (both in the
local shading frame, normal +z), so ``eval`` returns ``f(wi, wo) · cos θ_o``, with ``f``
exactly :meth:`frenbrdf.NBRDF.__call__` (network input H = (sin θ_h, 0, cos θ_h) and D,
as :func:`frenbrdf.models.nbrdf.nbrdf_coordinates`: the networks are trained with
φ_h = 0, and a half vector with another azimuth would ask them to extrapolate, to values
up to 1e180 near grazing for the published fits) or, for a table,
:func:`frenbrdf.merl_lookup_directions` clamped to ≥ 0. The surface is one-sided: zero
when either direction is below the horizon.

Evaluation is written in Dr.Jit and runs inside Mitsuba's kernels, never calling back
into numpy or torch: the NBRDF's matrix products are unrolled over its layers (weights
become constants of the compiled kernel), the per-bin reference BRDF of a log-relative
mapping and a MERL table are looked up trilinearly in MERL's bin coordinates by gathers
from a flat buffer, exactly as the native lookup does (corners without a measurement are
left out and the others renormalised; no measured corner gives 0).

Importance sampling
-------------------
Once per material (in numpy, well under a second) the BRDF along θ_h at small θ_d
is fitted by ``a + Σ_k b_k · D_αk(θ_h) · V_αk(θ_i, θ_o)`` (Lambert plus up to two GGX
microfacet lobes with height-correlated Smith visibility, non-negative weights, α on a
log grid). ``sample`` draws from the mixture of a cosine-weighted hemisphere (weight
≥ 0.1, so no direction is starved) and visible-normal sampling of each fitted GGX lobe
(weights ∝ the fitted lobe energies ``π a`` and ``b_k``); ``pdf`` is the exact mixture
density and the sample weight is ``f · cos θ_o / pdf``. Lobe samples reflected below the
horizon are failed samples (weight 0), so ``pdf`` integrates over the hemisphere to the
share of samples that succeed, 0.98–0.99 for a GGX α = 0.1 metal.

Variants
--------
Python BSDFs are practical only in Mitsuba's JIT variants: :func:`set_variant` picks
``llvm_ad_rgb`` when Dr.Jit's LLVM backend works and otherwise falls back to
``scalar_rgb`` with a warning; there the Python BSDF runs once per ray, about 8,000
samples per second on one core against millions (a 256×256, 64 spp sphere takes about
9 minutes instead of a second). Debian's ``libllvm19`` works
(``apt-get install -y libllvm19``); LLVM 14 is refused and LLVM 15 aborts the process
on the first kernel with a minimum or an arc tangent, which is why the backend is probed
once in a subprocess (:func:`llvm_available`) before it is used here.
"""

from __future__ import annotations

import functools
import itertools
import os
import subprocess
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .render import save_png, tonemap  # one tone mapping for both renderers
from .synth import ggx_d, ggx_visibility

#: The plugin's type name in Mitsuba scenes.
PLUGIN_NAME = "frenbrdf"
#: The variant used when it works.
PREFERRED_VARIANT = "llvm_ad_rgb"
#: The variant used when the LLVM backend is not available.
FALLBACK_VARIANT = "scalar_rgb"

_INSTALL_HINT = ("frenbrdf.mitsuba needs Mitsuba 3: pip install mitsuba (or pip install 'frenbrdf[mitsuba]'); "
                 "its fast llvm_ad_rgb variant also needs LLVM, e.g. apt-get install -y libllvm19")


def _import_mitsuba():
    """``(mitsuba, drjit)``, or an ImportError that says how to install them."""
    try:
        import drjit
        import mitsuba
    except ImportError as error:
        raise ImportError(f"{_INSTALL_HINT} ({error})") from error
    return mitsuba, drjit


# --------------------------------------------------------------------------- variants


# Every kind of operation the plugin compiles (LLVM 15 loads, then aborts on min/max and
# atan2), and a small render with a built-in BSDF.
_PROBE = """
import drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
x = dr.opaque(mi.Float, 0.5) * dr.arange(mi.Float, 16)
y = dr.maximum(dr.minimum(x, 3.0), 1.0) + dr.atan2(x, x + 1) + dr.exp(-x) + dr.sqrt(x) + dr.floor(x)
y += dr.gather(mi.Float, x, mi.UInt32(dr.round(x)) % 16)
dr.eval(y)
assert dr.all(dr.isfinite(y))
scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"}, "shape": {"type": "sphere"},
                      "light": {"type": "constant"},
                      "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 4, "height": 4}}})
assert dr.all(dr.isfinite(mi.render(scene, spp=2).array))
"""


@functools.cache
def llvm_available() -> bool:
    """Whether Mitsuba's ``llvm_ad_rgb`` variant works on this machine.

    Probed in a subprocess (a second or two, once per process) because Dr.Jit aborts the
    whole process, rather than raising, with an unsupported ``libLLVM``: it refuses LLVM
    14 cleanly, but LLVM 15 loads and then aborts when a kernel uses ``dr.minimum`` or
    ``dr.atan2``. ``DRJIT_LIBLLVM_PATH`` is honoured, as Dr.Jit honours it.
    """
    _import_mitsuba()
    try:
        result = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, timeout=300)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return result.returncode == 0


def set_variant(variant: str | None = None) -> str:
    """Selects the Mitsuba variant and returns its name.

    Parameters
    ----------
    variant
        A variant to use (e.g. ``"cuda_ad_rgb"``). By default: keep an RGB variant that
        is already set, else ``llvm_ad_rgb`` when the LLVM backend works, else
        ``scalar_rgb`` with a :class:`RuntimeWarning`.

    Raises
    ------
    ImportError
        Mitsuba is not installed (the message says ``pip install mitsuba``).
    ValueError
        ``variant`` is not one this Mitsuba build has, or is not an RGB variant.
    """
    mi, _ = _import_mitsuba()
    if variant is None:
        current = mi.variant()
        if current is not None and current.endswith("_rgb"):
            return current
        if llvm_available():
            variant = PREFERRED_VARIANT
        else:
            warnings.warn(f"Mitsuba's {PREFERRED_VARIANT} variant is not usable here (Dr.Jit's LLVM backend needs a "
                          f"recent libLLVM: apt-get install -y libllvm19); falling back to {FALLBACK_VARIANT}, "
                          "which evaluates the Python BSDF one ray at a time (hundreds of times slower)",
                          RuntimeWarning, stacklevel=2)
            variant = FALLBACK_VARIANT
    if variant not in mi.variants():
        raise ValueError(f"Mitsuba variant {variant!r} is not available; this build has {mi.variants()}")
    if not variant.endswith("_rgb"):
        raise ValueError(f"the frenbrdf plugin returns RGB reflectance and needs an *_rgb variant, got {variant!r}")
    mi.set_variant(variant)
    return variant


_REGISTERED: set[str] = set()


def register() -> str:
    """Registers the ``"frenbrdf"`` BSDF plugin with Mitsuba and returns the variant.

    Selects a variant first (:func:`set_variant`) if none is set. Registration is per
    variant: call again after switching variants. Calling twice is harmless.
    """
    mi, _ = _import_mitsuba()
    variant = set_variant()
    if variant not in _REGISTERED:
        cls = _bsdf_class(variant)
        mi.register_bsdf(PLUGIN_NAME, lambda props: cls(props))
        _REGISTERED.add(variant)
    return variant


# --------------------------------------------------------------------------- materials


@dataclass(frozen=True)
class Lobe:
    """One GGX lobe of the sampling mixture."""

    alpha: float
    """GGX roughness α."""
    weight: float
    """Probability of sampling this lobe."""


@dataclass(frozen=True)
class SamplingMixture:
    """How directions are sampled: a cosine-weighted hemisphere plus GGX lobes."""

    cosine: float
    """Probability of cosine-weighted hemisphere sampling."""
    lobes: tuple[Lobe, ...] = ()
    """The GGX lobes (visible-normal sampling, reflected about the sampled normal)."""

    def __post_init__(self):
        total = self.cosine + sum(lobe.weight for lobe in self.lobes)
        if not np.isclose(total, 1.0) or self.cosine < 0 or any(lobe.weight < 0 or lobe.alpha <= 0
                                                                  for lobe in self.lobes):
            raise ValueError(f"invalid sampling mixture {self}: weights must be ≥ 0 and sum to 1, α > 0")


COSINE_ONLY = SamplingMixture(1.0)

#: Smallest cosine-sampling probability of a fitted mixture (keeps weights bounded off the lobes).
MIN_COSINE_WEIGHT = 0.1
#: Candidate GGX roughness values of the fit.
ALPHA_GRID = tuple(float(a) for a in np.geomspace(0.004, 1.0, 36))


@dataclass(eq=False)
class Material:
    """A material in a form the plugin can evaluate (numpy side, independent of the variant).

    Use :func:`load_material` to build one from a path, an NBRDF or a table.
    """

    kind: str
    """``"nbrdf"`` or ``"merl"``."""
    name: str
    """For messages and the plugin's ``to_string``."""
    layers: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)
    """NBRDF: (weight ``(out, in)``, bias ``(out,)``) per layer, float32; ReLU between layers."""
    epsilon: float = 0.0
    """NBRDF: the mapping's ε."""
    reference: np.ndarray | None = None
    """NBRDF: f_ref, ``(3,)`` or a MERL-shaped table ``(3, 90, 90, 180)``."""
    table: np.ndarray | None = None
    """MERL: the table ``(3, 90, 90, 180)`` in physical units, missing bins negative."""
    nbrdf: object = None
    """NBRDF: the :class:`frenbrdf.NBRDF` itself (numpy evaluation)."""

    def brdf(self, wi, wo) -> np.ndarray:
        """Reference (numpy) evaluation: reflectance at direction pairs ``(..., 3)`` → ``(..., 3)``, ≥ 0."""
        if self.kind == "nbrdf":
            return self.nbrdf(wi, wo)
        from .merl import merl_lookup_directions

        return np.maximum(merl_lookup_directions(self.table, wi, wo, method="trilinear"), 0.0)

    @functools.cached_property
    def sampling(self) -> SamplingMixture:
        """The fitted importance-sampling mixture (computed once)."""
        return fit_sampling(self.brdf)

    @functools.cached_property
    def interleaved(self) -> np.ndarray:
        """The table (MERL) or the reference table (NBRDF) as float32 ``(N_BINS, 3)``."""
        source = self.table if self.kind == "merl" else self.reference
        return np.ascontiguousarray(source.reshape(3, -1).T, dtype=np.float32)


def material_from_nbrdf(nbrdf, name: str = "nbrdf") -> Material:
    """A :class:`Material` for one :class:`frenbrdf.NBRDF` (``len(nbrdf) == 1``)."""
    from .models.nbrdf import NBRDF

    if not isinstance(nbrdf, NBRDF):
        raise TypeError(f"expected an NBRDF, got {type(nbrdf).__name__}")
    if len(nbrdf) != 1:
        raise ValueError(f"this NBRDF holds {len(nbrdf)} materials; pass one, e.g. nbrdf[0]")
    params = [p[0].numpy().astype(np.float32) for p in nbrdf.params]
    layers = list(zip(params[0::2], params[1::2]))
    reference = np.asarray(nbrdf.mapping.reference, dtype=np.float64)
    return Material("nbrdf", name, layers=layers, epsilon=float(nbrdf.mapping.epsilon), reference=reference,
                    nbrdf=nbrdf)


def material_from_table(table, name: str = "merl") -> Material:
    """A :class:`Material` for a MERL table ``(3, 90, 90, 180)`` in physical units."""
    from .merl import SHAPE

    table = np.asarray(table, dtype=np.float64)
    if table.shape != SHAPE:
        raise ValueError(f"a MERL table must have shape {SHAPE}, got {table.shape}")
    if not np.all(np.isfinite(table)):
        raise ValueError(f"{name}: the MERL table holds NaN or inf values")
    return Material("merl", name, table=table)


def load_material(material) -> Material:
    """Any supported material → :class:`Material`.

    Parameters
    ----------
    material
        A :class:`frenbrdf.NBRDF` (one material); a MERL table array; a path to a MERL
        ``.binary`` file, to an NBRDF saved by :func:`frenbrdf.fitting.save_nbrdf`, or
        to a published Keras NBRDF ``.h5`` (see :mod:`frenbrdf.nbrdf_import`); a
        :func:`material_handle`; or a :class:`Material`.

    Raises
    ------
    FileNotFoundError
        The path does not exist.
    ValueError
        The file is none of the supported formats (the message names it).
    TypeError
        Anything else.
    """
    from .models.nbrdf import NBRDF

    if isinstance(material, Material):
        return material
    if isinstance(material, NBRDF):
        return material_from_nbrdf(material)
    if isinstance(material, np.ndarray):
        return material_from_table(material)
    if isinstance(material, str) and material in _HANDLES:
        return _HANDLES[material]
    if isinstance(material, (str, os.PathLike)):
        return _load_file(Path(material))
    raise TypeError(f"cannot render a {type(material).__name__}: pass an NBRDF, a MERL table, or a path to a "
                    "MERL file, a saved NBRDF or a Keras NBRDF .h5")


def _load_file(path: Path) -> Material:
    from .fitting import EXP_MINUS_ONE, load_nbrdf
    from .merl import FILE_BYTES, read_merl

    if not path.exists():
        raise FileNotFoundError(f"material file {path} does not exist")
    if path.suffix == ".h5":
        import torch

        from .models.nbrdf import NBRDF
        from .nbrdf_import import load_keras_nbrdf

        params = [torch.from_numpy(np.asarray(array, dtype=np.float32))[None]
                  for kernel, bias in load_keras_nbrdf(path) for array in (kernel.T, bias)]
        return material_from_nbrdf(NBRDF(params, EXP_MINUS_ONE), name=path.stem)
    if path.stat().st_size == FILE_BYTES:
        return material_from_table(read_merl(path), name=path.stem)
    try:
        return material_from_nbrdf(load_nbrdf(path), name=path.stem)
    except ValueError as error:
        raise ValueError(f"{path}: neither a MERL file ({FILE_BYTES} bytes) nor a saved NBRDF ({error})") from None


_HANDLES: dict[str, Material] = {}
_OWNERS: dict[str, object] = {}  # handle → the object it was made from (identity look-up)
_COUNTER = itertools.count()


def material_handle(material) -> str:
    """Keeps a material in memory under a name the plugin's ``material`` property accepts.

    The same in-memory object (NBRDF, table, :class:`Material`) always gets the same
    handle; it is read when the handle is made. The material stays referenced until
    :func:`release_handle` (scenes already loaded keep their own reference).
    """
    if isinstance(material, str) and material in _HANDLES:
        return material
    in_memory = not isinstance(material, (str, os.PathLike))
    if in_memory:
        for handle, owner in _OWNERS.items():
            if owner is material:
                return handle
    loaded = load_material(material)
    handle = f"frenbrdf:{loaded.kind}:{loaded.name}:{next(_COUNTER)}"
    _HANDLES[handle] = loaded
    if in_memory:
        _OWNERS[handle] = material
    return handle


def release_handle(handle: str) -> None:
    """Forgets a handle from :func:`material_handle` (scenes already loaded keep working)."""
    _HANDLES.pop(handle, None)
    _OWNERS.pop(handle, None)


def bsdf_dict(material, *, lookup: str = "trilinear", sampling: str = "fitted") -> dict:
    """The scene dictionary of a ``frenbrdf`` BSDF for any supported material.

    Files are referenced by path; in-memory materials through :func:`material_handle`.
    """
    entry = {"type": PLUGIN_NAME, "lookup": lookup, "sampling": sampling}
    if isinstance(material, (str, os.PathLike)) and not (isinstance(material, str) and material in _HANDLES):
        entry["filename"] = os.fspath(material)
    else:
        entry["material"] = material_handle(material)
    return entry


# --------------------------------------------------------------------------- sampling fit


def _nonnegative_least_squares(basis: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, float]:
    """min ‖basis · c − target‖² over c ≥ 0 for a few columns, by trying every active set."""
    n = basis.shape[1]
    best, best_residual = np.zeros(n), float(target @ target)
    for size in range(1, n + 1):
        for columns in itertools.combinations(range(n), size):
            sub = basis[:, columns]
            coefficients, *_ = np.linalg.lstsq(sub, target, rcond=None)
            if np.all(coefficients >= 0):
                residual = target - sub @ coefficients
                if residual @ residual < best_residual:
                    best = np.zeros(n)
                    best[list(columns)] = coefficients
                    best_residual = float(residual @ residual)
    return best, best_residual


def fit_sampling(brdf, max_lobes: int = 2) -> SamplingMixture:
    """Fits the importance-sampling mixture of a BRDF (see the module docstring).

    Parameters
    ----------
    brdf
        ``brdf(wi, wo) -> (..., 3)`` reflectance on local unit directions.
    max_lobes
        0, 1 or 2 GGX lobes. A second lobe is kept only if it lowers the residual by a
        third or more.

    Returns
    -------
    SamplingMixture
        Cosine weight ≥ :data:`MIN_COSINE_WEIGHT`; lobe weights ∝ fitted lobe energy.
    """
    from .coords import rusinkiewicz_to_directions

    # θ_h on MERL's quadratic axis (dense near the peak), two small θ_d, φ_d = π/2.
    theta_h = (np.linspace(0, 1, 121) ** 2) * (np.pi / 2)
    angles = np.array([[th, 0.0, td, np.pi / 2] for td in (0.05, 0.3) for th in theta_h])
    wi, wo = rusinkiewicz_to_directions(angles)
    keep = (wi[:, 2] > 0.05) & (wo[:, 2] > 0.05)
    wi, wo, cos_h = wi[keep], wo[keep], np.cos(angles[keep, 0])
    values = np.asarray(brdf(wi, wo), dtype=np.float64).mean(axis=-1)
    if not np.all(np.isfinite(values)) or values.max() <= 0:
        return COSINE_ONLY
    # Relative errors, floored so that the tails far below the peak do not dominate.
    scale = 1.0 / (values + 1e-3 * values.max())
    target = values * scale
    lobes = {alpha: ggx_d(cos_h, alpha) * ggx_visibility(wi[:, 2], wo[:, 2], alpha) for alpha in ALPHA_GRID}
    constant = np.ones_like(values)

    def fit(alphas):
        basis = np.stack([constant, *(lobes[a] for a in alphas)], axis=1) * scale[:, None]
        return _nonnegative_least_squares(basis, target)

    candidates = [((), *fit(()))]
    if max_lobes >= 1:
        candidates += [((a,), *fit((a,))) for a in ALPHA_GRID]
    best = min(candidates, key=lambda c: c[2])
    if max_lobes >= 2:
        pairs = [((a, b), *fit((a, b))) for a, b in itertools.combinations(ALPHA_GRID[::2], 2)]
        two = min(pairs, key=lambda c: c[2])
        if two[2] < 2 / 3 * best[2] and np.all(two[1][1:] > 0):
            best = two
    alphas, coefficients, _ = best
    # Energies: Lambert π a; a GGX lobe with weight b reflects about b.
    energies = np.array([np.pi * coefficients[0], *coefficients[1:]])
    if energies.sum() <= 0:
        return COSINE_ONLY
    share = energies / energies.sum()
    cosine = max(share[0], MIN_COSINE_WEIGHT)
    rest = share[1:] / max(share[1:].sum(), 1e-30) * (1 - cosine)
    lobes_out = tuple(Lobe(float(a), float(w)) for a, w in zip(alphas, rest) if w > 0)
    return SamplingMixture(float(1 - sum(lobe.weight for lobe in lobes_out)), lobes_out)


# --------------------------------------------------------------------------- Dr.Jit evaluation


class _Kernels:
    """The BRDF in Dr.Jit for the current variant: ``f(wi, wo)`` (no cosine), RGB."""

    def __init__(self, mi, dr, material: Material, lookup: str):
        self.mi, self.dr = mi, dr
        self.material = material
        self.lookup = lookup
        self.jit = dr.is_jit_v(mi.Float)
        self.buffer = None
        if material.kind == "merl" or (material.reference is not None and material.reference.ndim == 4):
            data = material.interleaved
            self.buffer = mi.Float(data.reshape(-1)) if self.jit else data
        if material.kind == "nbrdf":
            self.layers = [(w.astype(np.float64).tolist(), b.astype(np.float64).tolist())
                           for w, b in material.layers]

    # -- geometry

    def half_diff(self, wi, wo):
        """H and D (frenbrdf.half_diff_vectors) of unit or non-unit directions."""
        mi, dr = self.mi, self.dr
        wi, wo = dr.normalize(wi), dr.normalize(wo)
        s = wi + wo
        norm = dr.norm(s)
        h = dr.select(norm > 1e-12, s * dr.rcp(dr.maximum(norm, 1e-30)), mi.Vector3f(0, 0, 1))
        rho = dr.sqrt(dr.fma(h.x, h.x, h.y * h.y))
        pole = rho <= 0
        inv = dr.rcp(dr.maximum(rho, 1e-30))
        cos_t = dr.select(pole, dr.select(h.z < 0, -1.0, 1.0), h.z)
        sin_t = dr.select(pole, 0.0, rho)
        cos_p = dr.select(pole, 1.0, h.x * inv)
        sin_p = dr.select(pole, 0.0, h.y * inv)
        x = dr.fma(cos_p, wi.x, sin_p * wi.y)
        y = dr.fma(-sin_p, wi.x, cos_p * wi.y)
        d = mi.Vector3f(dr.fma(cos_t, x, -sin_t * wi.z), y, dr.fma(sin_t, x, cos_t * wi.z))
        return h, d

    def bin_coordinates(self, h, d):
        """Continuous MERL bin coordinates (θ_h, θ_d, φ_d indices) of H and D."""
        dr = self.dr
        half_pi = np.pi / 2
        theta_h = dr.atan2(dr.sqrt(dr.fma(h.x, h.x, h.y * h.y)), h.z)
        theta_d = dr.atan2(dr.sqrt(dr.fma(d.x, d.x, d.y * d.y)), d.z)
        phi_d = dr.atan2(d.y, d.x)
        i = dr.sqrt(dr.clip(theta_h, 0.0, half_pi) / half_pi) * 90.0
        j = dr.clip(theta_d, 0.0, half_pi) / half_pi * 90.0
        phi_d = dr.select(phi_d < 0, phi_d + np.pi, phi_d)
        k = phi_d / np.pi * 180.0
        k = dr.select(k >= 180.0, k - 180.0, k)
        return i, j, dr.clip(k, 0.0, 179.99998)

    def gather(self, bins, active):
        mi, dr = self.mi, self.dr
        if self.jit:
            return dr.gather(mi.Color3f, self.buffer, bins, active)
        return mi.Color3f(*(float(v) for v in self.buffer[int(bins)]))

    def table_lookup(self, i, j, k, active, method: str, masked: bool):
        """Trilinear (or nearest) lookup in the buffer; corners with negative values left out."""
        mi, dr = self.mi, self.dr
        UInt = mi.UInt32
        if method == "nearest":
            bins = (UInt(dr.minimum(dr.round(i), 89.0)) * 90 + UInt(dr.minimum(dr.round(j), 89.0))) * 180 \
                + UInt(dr.round(k)) % 180
            value = self.gather(bins, active)
            return dr.select(value >= 0, value, 0.0) if masked else value
        axes = []
        for x, n in ((i, 90), (j, 90)):
            x = dr.minimum(x, float(n - 1))
            lo = dr.floor(x)
            lo_i = UInt(lo)
            axes.append(((lo_i, 1.0 - (x - lo)), (dr.minimum(lo_i + 1, n - 1), x - lo)))
        k0 = dr.floor(k)
        k0_i = UInt(k0) % 180
        axes.append(((k0_i, 1.0 - (k - k0)), ((k0_i + 1) % 180, k - k0)))
        total = dr.zeros(mi.Color3f) if self.jit else mi.Color3f(0.0)
        weights = dr.zeros(mi.Color3f) if self.jit else mi.Color3f(0.0)
        for (bi, wi), (bj, wj), (bk, wk) in itertools.product(*axes):
            weight = wi * wj * wk
            value = self.gather((bi * 90 + bj) * 180 + bk, active)
            if masked:
                valid = value >= 0
                total += dr.select(valid, weight * value, 0.0)
                weights += dr.select(valid, weight, 0.0)
            else:
                total += weight * value
        if not masked:
            return total
        return dr.select(weights > 0, total / dr.maximum(weights, 1e-30), 0.0)

    # -- the BRDF

    def mlp(self, h, d):
        """The NBRDF's network at (H, D) with φ_h = 0: mapped RGB (three floats)."""
        dr = self.dr
        # The network was trained on H = (sin θ_h, 0, cos θ_h): drop H's azimuth (isotropy),
        # as frenbrdf.models.nbrdf.nbrdf_coordinates does.
        x = [dr.sqrt(dr.fma(h.x, h.x, h.y * h.y)), None, h.z, d.x, d.y, d.z]
        last = len(self.layers) - 1
        for index, (weight, bias) in enumerate(self.layers):
            out = []
            for row, b in zip(weight, bias):
                acc = None
                for w, xi in zip(row, x):
                    if w == 0.0 or xi is None:
                        continue
                    acc = xi * w + b if acc is None else dr.fma(xi, w, acc)
                if acc is None:
                    acc = x[0] * 0.0 + b
                out.append(dr.maximum(acc, 0.0) if index < last else acc)
            x = out
        return x

    def __call__(self, wi, wo, active):
        """Reflectance f(wi, wo) ≥ 0, RGB; meaningful where ``active``."""
        mi, dr = self.mi, self.dr
        h, d = self.half_diff(wi, wo)
        if self.material.kind == "merl":
            i, j, k = self.bin_coordinates(h, d)
            return self.table_lookup(i, j, k, active, self.lookup, masked=True)
        y = mi.Color3f(*self.mlp(h, d))
        eps = self.material.epsilon
        if self.buffer is None:
            reference = mi.Color3f(*(float(r) + eps for r in self.material.reference))
        else:
            i, j, k = self.bin_coordinates(h, d)
            reference = dr.maximum(self.table_lookup(i, j, k, active, "trilinear", masked=False), 0.0) + eps
        return dr.maximum(dr.fma(reference, dr.exp(y), -eps), 0.0)


@functools.cache
def _bsdf_class(variant: str):
    """The plugin class for a variant (Mitsuba's BSDF base class differs per variant)."""
    mi, dr = _import_mitsuba()
    if mi.variant() != variant:
        raise RuntimeError(f"the Mitsuba variant is {mi.variant()!r}, expected {variant!r}")

    class FreNBRDFBSDF(mi.BSDF):
        """A MERL table or NBRDF as a Mitsuba BSDF (see :mod:`frenbrdf.mitsuba`)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            filename = props.get("filename", None)
            handle = props.get("material", None)
            lookup = str(props.get("lookup", "trilinear"))
            sampling = str(props.get("sampling", "fitted"))
            if (filename is None) == (handle is None):
                raise ValueError("the frenbrdf BSDF needs exactly one of 'filename' (a MERL file, saved NBRDF or "
                                 "Keras .h5) and 'material' (a handle from frenbrdf.mitsuba.material_handle)")
            if handle is not None and handle not in _HANDLES:
                raise ValueError(f"unknown material handle {handle!r}: create it with "
                                 "frenbrdf.mitsuba.material_handle() in this process")
            if lookup not in ("trilinear", "nearest"):
                raise ValueError(f"lookup must be 'trilinear' or 'nearest', got {lookup!r}")
            if sampling not in ("fitted", "cosine"):
                raise ValueError(f"sampling must be 'fitted' or 'cosine', got {sampling!r}")
            self.material = _HANDLES[handle] if handle is not None else _load_file(Path(filename))
            self.kernels = _Kernels(mi, dr, self.material, lookup)
            self.mixture = self.material.sampling if sampling == "fitted" else COSINE_ONLY
            self.distributions = [mi.MicrofacetDistribution(mi.MicrofacetType.GGX, lobe.alpha, True)
                                  for lobe in self.mixture.lobes]
            flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def _pdf(self, wi, wo, active):
            pdf = self.mixture.cosine * mi.warp.square_to_cosine_hemisphere_pdf(wo)
            if self.mixture.lobes:
                m = dr.normalize(wi + wo)
                jacobian = dr.rcp(dr.maximum(4.0 * dr.dot(wo, m), 1e-20))
                for lobe, distribution in zip(self.mixture.lobes, self.distributions):
                    pdf += lobe.weight * distribution.pdf(wi, m) * jacobian
            return dr.select(active, pdf, 0.0)

        def _active(self, ctx, si, wo, active):
            enabled = ctx.is_enabled(mi.BSDFFlags.GlossyReflection)
            cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
            return active & (cos_i > 0) & (cos_o > 0) & enabled, cos_o

        def eval(self, ctx, si, wo, active=True):
            active, cos_o = self._active(ctx, si, wo, active)
            return dr.select(active, self.kernels(si.wi, wo, active) * cos_o, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            active, _ = self._active(ctx, si, wo, active)
            return self._pdf(si.wi, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            active, cos_o = self._active(ctx, si, wo, active)
            value = dr.select(active, self.kernels(si.wi, wo, active) * cos_o, 0.0)
            return value, self._pdf(si.wi, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = si.wi
            active = active & (mi.Frame3f.cos_theta(wi) > 0) & ctx.is_enabled(mi.BSDFFlags.GlossyReflection)
            wo = mi.warp.square_to_cosine_hemisphere(sample2)
            threshold = self.mixture.cosine
            for lobe, distribution in zip(self.mixture.lobes, self.distributions):
                m, _ = distribution.sample(wi, sample2)
                wo = dr.select(sample1 >= threshold, mi.reflect(wi, m), wo)
                threshold += lobe.weight
            cos_o = mi.Frame3f.cos_theta(wo)
            active &= cos_o > 0
            pdf = self._pdf(wi, wo, active)
            active &= pdf > 0
            value = self.kernels(wi, wo, active) * cos_o
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = wo
            bs.pdf = pdf
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            weight = dr.select(active, value / dr.maximum(pdf, 1e-30), 0.0)
            return bs, weight

        def traverse(self, callback):
            pass

        def to_string(self):
            lobes = ", ".join(f"GGX α={lobe.alpha:.3g} p={lobe.weight:.2f}" for lobe in self.mixture.lobes)
            return (f"FreNBRDF[{self.material.kind} {self.material.name!r}, "
                    f"sampling: cosine p={self.mixture.cosine:.2f}{', ' + lobes if lobes else ''}]")

    return FreNBRDFBSDF


# --------------------------------------------------------------------------- rendering


def environment_bitmap(width: int = 128) -> np.ndarray:
    """The analytic environment of :func:`render_material`, latitude-longitude float32 ``(width/2, width, 3)``.

    A soft sky (bluish at the zenith, warm at the horizon), a dark ground and a small
    bright sun; Mitsuba's envmap convention (+y up, rows from the zenith down, column u
    at the direction (sin 2πu sin θ, cos θ, −cos 2πu sin θ)).
    """
    height = width // 2
    theta = (np.arange(height) + 0.5) / height * np.pi
    phi = (np.arange(width) + 0.5) / width * 2 * np.pi
    up = np.cos(theta)[:, None, None] * np.ones((1, width, 1))
    sky = np.array([0.35, 0.45, 0.6]) * np.clip(up, 0, 1) + np.array([0.5, 0.42, 0.35]) * (1 - np.abs(up))
    ground = np.array([0.08, 0.07, 0.06]) * np.ones_like(sky)
    image = np.where(up > 0, sky, ground) * 0.6
    # A sun 50° above the horizon, up and to the right of the camera's view, about 3° in radius.
    sun_theta, sun_phi = np.radians(40.0), np.radians(130.0)

    def direction(t, p):
        return np.stack(np.broadcast_arrays(np.sin(p) * np.sin(t), np.cos(t), -np.cos(p) * np.sin(t)), axis=-1)

    cos_angle = direction(theta[:, None], phi[None, :]) @ direction(sun_theta, sun_phi)
    image += np.where(cos_angle > np.cos(np.radians(3.0)), 40.0, 0.0)[..., None] * np.array([1.0, 0.95, 0.85])
    return image.astype(np.float32)


def scene_dict(bsdf: dict, *, resolution: int = 256, spp: int = 64, scene: str = "sphere") -> dict:
    """The Mitsuba scene of :func:`render_material`: a unit sphere with ``bsdf``.

    A perspective camera on +z, the :func:`environment_bitmap` environment and two
    directional lights, a path tracer of depth 3.
    """
    mi, _ = _import_mitsuba()
    if scene != "sphere":
        raise ValueError(f"unknown scene {scene!r}; available: 'sphere'")
    if resolution < 1 or spp < 1:
        raise ValueError(f"resolution and spp must be ≥ 1, got {resolution} and {spp}")
    lights = {"key": ((-0.5, 0.6, 0.62), (2.2, 2.1, 2.0)), "fill": ((0.7, 0.2, 0.68), (0.9, 0.95, 1.1))}
    emitters = {name: {"type": "directional", "direction": [-c for c in towards],
                       "irradiance": {"type": "rgb", "value": list(colour)}}
                for name, (towards, colour) in lights.items()}
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {
            "type": "perspective",
            "fov": 30.0,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4.5], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": resolution, "height": resolution, "pixel_format": "rgb",
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sphere": {"type": "sphere", "radius": 1.0, "bsdf": bsdf},
        "environment": {"type": "envmap", "bitmap": mi.Bitmap(environment_bitmap())},
        **emitters,
    }


def render_material(material, out_path: str | os.PathLike | None = None, spp: int = 64, resolution: int = 256,
                    scene: str = "sphere", *, seed: int = 0, sampling: str = "fitted",
                    exposure: float = 1.0) -> np.ndarray:
    """Renders a material on a sphere in Mitsuba 3.

    Parameters
    ----------
    material
        A MERL path, an NBRDF, a saved-NBRDF path, a Keras ``.h5`` or a MERL table
        (anything :func:`load_material` takes).
    out_path
        If given, also write a PNG there (atomically): exposure → clamp → gamma 2.2.
    spp, resolution
        Samples per pixel; image width and height.
    scene
        ``"sphere"`` (the only one).
    seed
        The sampler's seed.
    sampling
        ``"fitted"`` importance sampling or ``"cosine"`` only.
    exposure
        Multiplier applied to the PNG only.

    Returns
    -------
    numpy.ndarray
        Linear RGB radiance, float32 ``(resolution, resolution, 3)``.
    """
    mi, _ = _import_mitsuba()
    register()
    known = isinstance(material, str) and material in _HANDLES
    handle = material_handle(material)
    try:
        scene_object = mi.load_dict(scene_dict(bsdf_dict(handle, sampling=sampling), resolution=resolution, spp=spp,
                                               scene=scene))
        image = np.array(mi.render(scene_object, spp=spp, seed=seed), dtype=np.float32)
    finally:
        if not known:
            release_handle(handle)
    if out_path is not None:
        save_png(out_path, tonemap(image, exposure))
    return image
