"""Importance sampling: a Lambert + GGX mixture fitted once per material (see :mod:`frenbrdf.render.mitsuba`)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ...data.microfacet import ggx_d, ggx_visibility


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


#: Cosine-weighted hemisphere sampling alone: ``sampling="cosine"``, and the fit's result when there is nothing to
#: fit (a BRDF that is zero or not finite).
COSINE_ONLY = SamplingMixture(1.0)

#: Smallest cosine-sampling probability of a fitted mixture (keeps weights bounded off the lobes).
MIN_COSINE_WEIGHT = 0.1
#: Candidate GGX roughness values of the fit.
ALPHA_GRID = tuple(float(a) for a in np.geomspace(0.004, 1.0, 36))



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
    from ...numerics.coords import rusinkiewicz_to_directions

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
    lobes_out = tuple(Lobe(float(a), float(w)) for a, w in zip(alphas, rest, strict=True) if w > 0)
    return SamplingMixture(float(1 - sum(lobe.weight for lobe in lobes_out)), lobes_out)

