"""The one check a material's values pass on their way in, whatever file they come from.

A MERL ``.binary`` table (:func:`frenbrdf.io.merl.read_merl`), an RGL ``.bsdf`` measurement
(:func:`frenbrdf.io.bsdf.read_bsdf`, and its table at the MERL bins) and therefore everything
that trains on, reconstructs, converts or renders them go through :func:`check_reflectance`:
training and reconstruction refuse the same files, with the same message.
"""

from __future__ import annotations

import numpy as np

#: The largest reflectance (1/sr) frenbrdf takes: MERL's grazing spikes reach 10⁵ and the RGL
#: measurements 10⁷; far larger values overflow the networks' float32 (the log mapping turns 10³⁰
#: into a target the refinement overshoots to inf).
MAX_REFLECTANCE = 1e8


def check_reflectance(values, source, *, what: str = "values", axes: str = "",
                      error: type[ValueError] = ValueError) -> None:
    """Raises ``error`` unless every value is finite and at most :data:`MAX_REFLECTANCE`.

    Negative values pass: MERL tables mark missing bins with them (and measurements hold slightly
    negative noise); readers of samples that have no missing ones check ≥ 0 themselves.

    Parameters
    ----------
    values
        Any array of reflectance in 1/sr.
    source
        What the values were read from (a path): every message starts with it.
    what
        What the values are, for the message (``"values of field rgb"``).
    axes
        Names of ``values``' axes, for the message (``"(channel, θ_h, θ_d, φ_d)"``).
    error
        The exception class to raise (a format error of the reader, a ValueError subclass).

    Raises
    ------
    ValueError
        ``error``: how many values are NaN or infinite, or above the limit, and where the first is.
    """
    values = np.asarray(values)
    if values.size == 0:
        return
    # Two reductions and no temporary on the way through: a NaN anywhere makes the max NaN, and
    # the comparison False; -inf shows in the min.
    top, bottom = float(np.max(values)), float(np.min(values))
    if top <= MAX_REFLECTANCE and np.isfinite(bottom):
        return
    where = f" {axes}" if axes else ""
    bad = ~np.isfinite(values)
    if bad.any():
        first = np.unravel_index(int(np.argmax(bad)), values.shape)
        raise error(f"{source}: {int(bad.sum()):,} of its {what} are NaN or infinite (the first at index{where} "
                    f"{tuple(int(i) for i in first)})")
    over = values > MAX_REFLECTANCE
    first = np.unravel_index(int(np.argmax(over)), values.shape)
    raise error(f"{source}: {int(over.sum()):,} of its {what} are above {MAX_REFLECTANCE:g} 1/sr (the largest is {top:.4g}, "
                f"the first at index{where} {tuple(int(i) for i in first)}); MERL's highest spikes are about 1e5 and "
                "real measurements stay below 1e7: is the unit right?")
