"""Mitsuba variants: which one to use, probing Dr.Jit's LLVM backend safely, and registration."""

from __future__ import annotations

import functools
import subprocess
import sys
import warnings

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
