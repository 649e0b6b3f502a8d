"""Render MERL tables, measurements and NBRDFs in Mitsuba 3: a BSDF plugin evaluated in Dr.Jit.

:func:`register` adds a BSDF plugin named ``"frenbrdf"`` to Mitsuba, so any Mitsuba 3
scene can use a measured MERL table, an RGL ``.bsdf`` or a neural BRDF::

    from frenbrdf import mitsuba as fm   # before mitsuba: it may point Dr.Jit at a libLLVM first
    import mitsuba as mi

    fm.set_variant()                     # llvm_ad_rgb, or scalar_rgb with a warning
    fm.register()
    scene = mi.load_dict({..., "shape": {"type": "sphere",
                                         "bsdf": fm.bsdf_dict("gold.binary")}})

or, without writing a scene, :func:`render_material` renders a sphere under an
environment and two directional lights.

The plugin
----------
``{"type": "frenbrdf", ...}`` takes

- ``filename``: a MERL ``.binary`` file, an RGL ``.bsdf`` measurement, a saved NBRDF ``.pt``, or a
  published Keras NBRDF ``.h5`` (read by :func:`frenbrdf.io.read_material`); or
- ``material``: a handle from :func:`material_handle` for a material held in memory (an
  :class:`frenbrdf.NBRDF`, a MERL table array, a :func:`frenbrdf.read_bsdf` measurement):
  Mitsuba's properties hold only numbers, strings and Mitsuba objects, so Python objects travel
  by name (a handle keeps its material in memory until :func:`release_handle`);
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
when either direction is below the horizon. An ordered NBRDF (:attr:`frenbrdf.NBRDF.ordered`, one that
tells the two orders of a pair apart, as a refined real measurement may) is the exception: it is
evaluated as ``f(wo, si.wi)``, the light's direction first, as the metric renderer and the
measurements take it (``si.wi`` points to the camera). So is a ``.bsdf`` measurement, which is not
reciprocal near grazing: it is evaluated as it is, never through a quantised table, by Mitsuba's own
``measured`` BSDF (which alone would take ``si.wi`` first) at the pair in that order.

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
9 minutes instead of a second). LLVM 19 works (Debian's ``libllvm19``); LLVM 14 is
refused and LLVM 15 aborts the process on the first kernel with a minimum or an arc
tangent, which is why the backend is probed once in a subprocess (:func:`llvm_available`)
before it is used here. The ``mitsuba`` extra installs LLVM 19.1.7 from PyPI
(:data:`LLVM_PACKAGE`, Linux x86-64): when the system has no libLLVM that works, the
first use of this module, before it imports drjit, points Dr.Jit at that one by setting
``DRJIT_LIBLLVM_PATH`` (:func:`use_packaged_llvm`; a path already set is kept).
"""

from .bsdf import register
from .material import (
    _HANDLES,
    Material,
    bsdf_dict,
    load_material,
    material_from_measurement,
    material_from_nbrdf,
    material_from_table,
    material_handle,
    release_handle,
)
from .sampling import ALPHA_GRID, COSINE_ONLY, MIN_COSINE_WEIGHT, Lobe, SamplingMixture, fit_sampling
from .scene import environment_bitmap, render_material, save_png, scene_dict, tonemap
from .variants import (
    FALLBACK_VARIANT,
    LIBLLVM_VARIABLE,
    LLVM_PACKAGE,
    PLUGIN_NAME,
    PREFERRED_VARIANT,
    llvm_available,
    packaged_libllvm,
    set_variant,
    use_packaged_llvm,
)

__all__ = [
    "ALPHA_GRID", "COSINE_ONLY", "FALLBACK_VARIANT", "LIBLLVM_VARIABLE", "LLVM_PACKAGE", "MIN_COSINE_WEIGHT",
    "PLUGIN_NAME", "PREFERRED_VARIANT", "Lobe", "Material", "SamplingMixture", "_HANDLES", "bsdf_dict",
    "environment_bitmap", "fit_sampling", "llvm_available", "load_material", "material_from_measurement",
    "material_from_nbrdf", "material_from_table", "material_handle", "packaged_libllvm", "register",
    "release_handle", "render_material", "save_png", "scene_dict", "set_variant", "tonemap", "use_packaged_llvm",
]
