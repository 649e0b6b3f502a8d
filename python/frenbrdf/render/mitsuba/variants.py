"""Mitsuba variants: which one to use, which libLLVM Dr.Jit loads, and probing its LLVM backend safely."""

from __future__ import annotations

import functools
import importlib.metadata
import os
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

#: The plugin's type name in Mitsuba scenes.
PLUGIN_NAME = "frenbrdf"
#: The variant used when it works.
PREFERRED_VARIANT = "llvm_ad_rgb"
#: The variant used when the LLVM backend is not available.
FALLBACK_VARIANT = "scalar_rgb"

#: The PyPI package whose wheel ships a libLLVM Dr.Jit can load (LLVM 19.1.7, Linux x86-64); the
#: ``mitsuba`` extra installs it, for machines without a system LLVM that works.
LLVM_PACKAGE = "karellen-llvm-core"
#: Dr.Jit's variable for the libLLVM to load; read once, when drjit is first imported.
LIBLLVM_VARIABLE = "DRJIT_LIBLLVM_PATH"

_INSTALL_HINT = ("frenbrdf.render.mitsuba needs Mitsuba 3: pip install mitsuba, or pip install 'frenbrdf[mitsuba]', which "
                 f"also installs {LLVM_PACKAGE}, a libLLVM for its fast llvm_ad_rgb variant")


def _import_mitsuba() -> tuple[Any, Any]:
    """``(mitsuba, drjit)``, or an ImportError that says how to install them. (Typed Any: what the modules hold,
    ``mi.BSDF`` for one, depends on the variant set at run time.)

    Before drjit's first import, points Dr.Jit at the pip-installed libLLVM if the
    system's does not work (:func:`use_packaged_llvm`).
    """
    use_packaged_llvm()
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
def _llvm_works(libllvm: str | None) -> bool:
    """Whether the probe passes with Dr.Jit loading ``libllvm`` (None: the one Dr.Jit finds by itself)."""
    env = {name: value for name, value in os.environ.items() if name != LIBLLVM_VARIABLE}
    if libllvm is not None:
        env[LIBLLVM_VARIABLE] = libllvm
    try:
        result = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, timeout=300, env=env)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return result.returncode == 0


def llvm_available() -> bool:
    """Whether Mitsuba's ``llvm_ad_rgb`` variant works in this process.

    Probed in a subprocess (a second or two, once per process and library) because
    Dr.Jit aborts the whole process, rather than raising, with an unsupported ``libLLVM``:
    it refuses LLVM 14 cleanly, but LLVM 15 loads and then aborts when a kernel uses
    ``dr.minimum`` or ``dr.atan2``. ``DRJIT_LIBLLVM_PATH`` is honoured, as Dr.Jit honours it.
    """
    _import_mitsuba()
    return _llvm_works(os.environ.get(LIBLLVM_VARIABLE))


def packaged_libllvm() -> str | None:
    """The libLLVM of the pip package :data:`LLVM_PACKAGE`, or None when it is not installed.

    The wheel installs ``libLLVM.so.19.1`` under the environment's ``lib/`` (a data file,
    found through the package's file list) beside its own libc++, whose ``.so.1`` links
    the package's start-up hook makes on the first Python start after the install.
    """
    try:
        files = importlib.metadata.files(LLVM_PACKAGE) or []
    except importlib.metadata.PackageNotFoundError:
        return None
    for file in files:
        if file.name.startswith("libLLVM.so."):
            path = Path(file.locate()).resolve()
            if path.is_file():
                return str(path)
    return None


def use_packaged_llvm() -> str | None:
    """Points Dr.Jit at :func:`packaged_libllvm` when the system has no libLLVM that works.

    Sets ``DRJIT_LIBLLVM_PATH`` in this process (children inherit it), and only if it is
    unset and drjit is not imported yet: Dr.Jit reads it once, at import, and a path the
    user chose is kept. Costs one probe (:func:`llvm_available` reuses it) the first time,
    when the package is installed. Returns the path Dr.Jit is pointed at, or None.
    """
    if LIBLLVM_VARIABLE in os.environ or "drjit" in sys.modules:
        return os.environ.get(LIBLLVM_VARIABLE)
    packaged = packaged_libllvm()
    if packaged is None or _llvm_works(None):
        return None
    os.environ[LIBLLVM_VARIABLE] = packaged
    return packaged


def _llvm_hint() -> str:
    """How to get a libLLVM that works, for the fallback warning."""
    packaged = packaged_libllvm()
    if packaged is None:
        return f"pip install {LLVM_PACKAGE} (Linux x86-64) or apt-get install -y libllvm19"
    if os.environ.get(LIBLLVM_VARIABLE) == packaged:
        return f"{LLVM_PACKAGE}'s {packaged} does not work here either"
    return (f"{LLVM_PACKAGE}'s works where the system's does not: import frenbrdf.render.mitsuba before mitsuba and "
            f"drjit (it then points Dr.Jit at it), or set {LIBLLVM_VARIABLE}={packaged} before drjit is imported")


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
                          f"recent libLLVM: 19 works, 14 and 15 do not; {_llvm_hint()}); falling back to "
                          f"{FALLBACK_VARIANT}, which evaluates the Python BSDF one ray at a time (hundreds of times "
                          "slower)", RuntimeWarning, stacklevel=2)
            variant = FALLBACK_VARIANT
    if variant not in mi.variants():
        raise ValueError(f"Mitsuba variant {variant!r} is not available; this build has {mi.variants()}")
    if not variant.endswith("_rgb"):
        raise ValueError(f"the frenbrdf plugin returns RGB reflectance and needs an *_rgb variant, got {variant!r}")
    mi.set_variant(variant)
    return variant
