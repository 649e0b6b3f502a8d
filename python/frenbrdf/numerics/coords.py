"""Rusinkiewicz half/difference coordinates.

H = normalize(ω_i + ω_o) has spherical angles (θ_h, φ_h). D is ω_i expressed in the
frame that rotates H to the pole, with angles (θ_d, φ_d). Polar angles lie in [0, π],
azimuths in (−π, π]. Swapping ω_i and ω_o (reciprocity) leaves θ_h, φ_h, θ_d unchanged
and shifts φ_d by π. All functions take arrays of any leading shape ``(..., 3)`` or
``(..., 4)`` and run in parallel in the native core.

Examples
--------
>>> import numpy as np, frenbrdf
>>> wi = np.array([0.0, 0.6, 0.8]); wo = np.array([0.0, -0.6, 0.8])
>>> frenbrdf.directions_to_rusinkiewicz(wi, wo).round(4)   # specular: θ_h = 0
array([0.    , 0.    , 0.6435, 1.5708])
"""

from __future__ import annotations

import numpy as np

from .. import _native
from ._arrays import rows


def _pair(wi, wo) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    wi_rows, leading = rows("wi", wi, 3)
    wo_rows, _ = rows("wo", wo, 3)
    if np.shape(wi) != np.shape(wo):
        raise ValueError(f"wi and wo must have the same shape, got {np.shape(wi)} and {np.shape(wo)}")
    return wi_rows, wo_rows, leading


def directions_to_rusinkiewicz(wi, wo) -> np.ndarray:
    """Direction pairs ``(..., 3)`` → angles (θ_h, φ_h, θ_d, φ_d) ``(..., 4)``.

    Directions need not be normalised but must be finite and non-zero. Where
    ω_i = −ω_o (opposite grazing directions) H is undefined and taken as the pole.
    """
    wi_rows, wo_rows, leading = _pair(wi, wo)
    return _native.directions_to_rusinkiewicz(wi_rows, wo_rows).reshape(*leading, 4)


def rusinkiewicz_to_directions(angles) -> tuple[np.ndarray, np.ndarray]:
    """Angles (θ_h, φ_h, θ_d, φ_d) ``(..., 4)`` → unit directions (ω_i, ω_o), each ``(..., 3)``."""
    flat, leading = rows("angles", angles, 4)
    wi, wo = _native.rusinkiewicz_to_directions(flat)
    return wi.reshape(*leading, 3), wo.reshape(*leading, 3)


def half_diff_vectors(wi, wo) -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs → the NBRDF input: unit half vector H and difference vector D."""
    wi_rows, wo_rows, leading = _pair(wi, wo)
    h, d = _native.half_diff_vectors(wi_rows, wo_rows)
    return h.reshape(*leading, 3), d.reshape(*leading, 3)


def rusinkiewicz_to_half_diff(angles) -> tuple[np.ndarray, np.ndarray]:
    """Angles (θ_h, φ_h, θ_d, φ_d) ``(..., 4)`` → Cartesian H and D, each ``(..., 3)``."""
    flat, leading = rows("angles", angles, 4)
    h, d = _native.rusinkiewicz_to_half_diff(flat)
    return h.reshape(*leading, 3), d.reshape(*leading, 3)
