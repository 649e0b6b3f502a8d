"""Where the analytic BRDFs are evaluated, and what they reflect: direction-pair geometry and
tabulated directional albedos.

:class:`Geometry` holds the cosines a lobe depends on (and the directions, for the
retro-reflective half vector); :func:`geometry` builds it for direction pairs and
:func:`merl_geometry` for every MERL bin. :func:`directional_albedo` tabulates
``E(μ) = ∫ f μ_o dω_o`` of a lobe on a grid of ``μ`` by a deterministic quadrature whose half
vectors follow the lobe's GGX distribution (so near-mirror lobes are resolved); :class:`Albedo`
interpolates it. :mod:`frenbrdf.data.analytic` builds its materials on both.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..io.merl import merl_bin_directions, merl_bin_grid
from .microfacet import ggx_d


@dataclass(frozen=True)
class Geometry:
    """The cosines a BRDF depends on, each broadcastable to ``(..., 1)``.

    Cosines are clamped to (0, 1] so that lobes stay finite where a direction is below
    the horizon; ``above`` marks the pairs where the BRDF is not zero. ``wi`` and ``wo``
    are the unit directions, kept for the retro-reflective half vector (:attr:`cos_back`).
    """

    cos_i: np.ndarray
    cos_o: np.ndarray
    cos_h: np.ndarray
    cos_d: np.ndarray
    above: np.ndarray
    wi: np.ndarray
    wo: np.ndarray

    @functools.cached_property
    def cos_back(self) -> np.ndarray:
        """cos θ of the *back* half vector ``normalize(ω_i + ω̄_o)``, ``ω̄_o`` being ``ω_o``
        turned by π about the normal: 1 where ``ω_o = ω_i`` (retro-reflection). Swapping
        ``ω_i`` and ``ω_o`` turns this half vector by π, so its cosine is reciprocal."""
        back = self.wi + self.wo * np.array([-1.0, -1.0, 1.0])
        return _clamped(back[..., 2:] / np.maximum(np.linalg.norm(back, axis=-1, keepdims=True), _TINY))


_TINY = 1e-12


def _clamped(cos: np.ndarray) -> np.ndarray:
    return np.clip(cos, _TINY, 1.0)


def geometry(wi: np.ndarray, wo: np.ndarray) -> Geometry:
    """Geometry of direction pairs ``(..., 3)`` (normalised here)."""
    wi = wi / np.linalg.norm(wi, axis=-1, keepdims=True)
    wo = wo / np.linalg.norm(wo, axis=-1, keepdims=True)
    h = wi + wo
    h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), _TINY)  # ω_i = −ω_o: below the horizon
    cos_i, cos_o = wi[..., 2:], wo[..., 2:]
    return Geometry(cos_i=_clamped(cos_i), cos_o=_clamped(cos_o), cos_h=_clamped(h[..., 2:]),
                    cos_d=_clamped(np.sum(wi * h, axis=-1, keepdims=True)), above=(cos_i > 0) & (cos_o > 0),
                    wi=wi, wo=wo)


@functools.lru_cache(maxsize=1)
def merl_geometry() -> Geometry:
    """Geometry of every MERL bin (φ_h = 0), computed once.

    θ_h and θ_d are the bin angles themselves, so they stay on their own axes
    (``(90, 1, 1, 1)`` and ``(1, 90, 1, 1)``): Fresnel and D are then evaluated at 90
    values rather than 1.458M. Only μ_i and μ_o are full ``(90, 90, 180, 1)`` arrays.
    """
    grid = merl_bin_grid()
    wi, wo = merl_bin_directions()
    cos_i, cos_o = wi[..., 2:].copy(), wo[..., 2:].copy()
    theta_h, theta_d = grid[:, 0, 0, 0], grid[0, :, 0, 1]
    return Geometry(cos_i=_clamped(cos_i), cos_o=_clamped(cos_o),
                    cos_h=np.cos(theta_h).reshape(90, 1, 1, 1), cos_d=np.cos(theta_d).reshape(1, 90, 1, 1),
                    above=(cos_i > 0) & (cos_o > 0), wi=wi, wo=wo)


#: μ = cos θ nodes of the albedo tables, denser towards grazing where albedos change fastest.
_MU_NODES = np.maximum(np.linspace(0.0, 1.0, 96) ** 2, 1e-4)
_QUADRATURE_NODES = 48  # per axis, per μ node
# The white (F = 1) retro lobe needs a finer rule: at 48 its albedo at grazing incidence is ~0.2 % low
# (so a white retro-reflective base reflected ~0.2 % more than it receives); at 96, 0.1 %.
RETRO_QUADRATURE_NODES = 96


@dataclass(frozen=True)
class Albedo:
    """A tabulated directional albedo E(μ) per channel and its average Ē = 2 ∫ E μ dμ."""

    values: np.ndarray  # (len(_MU_NODES), channels)
    average: np.ndarray  # (channels,)

    def __call__(self, cos: np.ndarray) -> np.ndarray:
        """E at cosines ``(..., 1)`` → ``(..., channels)``, linear between nodes."""
        flat = cos.reshape(-1)
        columns = [np.interp(flat, _MU_NODES, column) for column in self.values.T]
        return np.stack(columns, axis=-1).reshape(*cos.shape[:-1], len(columns))

    def __add__(self, other: Albedo) -> Albedo:
        """The albedo of the sum of two lobes (channels broadcast)."""
        return Albedo(values=self.values + other.values, average=self.average + other.average)


def _hemisphere_rule(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Product rule on [0, 1] × [0, 2π): Gauss–Legendre in u, midpoints in φ; weights sum to 1."""
    x, w = np.polynomial.legendre.leggauss(n)
    u, phi = np.meshgrid((x + 1.0) / 2.0, (np.arange(n) + 0.5) * (2.0 * np.pi / n), indexing="ij")
    weights = np.broadcast_to((w / 2.0)[:, None] / n, u.shape)
    return u.reshape(-1), phi.reshape(-1), weights.reshape(-1)


def directional_albedo(lobe: Callable[[Geometry], np.ndarray | float], alpha: float | None,
                       nodes: int = _QUADRATURE_NODES) -> Albedo:
    """Tabulates E(μ) = ∫ f μ_o dω_o of ``lobe`` at ``_MU_NODES``.

    ``alpha`` given: the half vector follows the GGX distribution of that roughness
    (tan² θ_h = α² u / (1 − u), so D μ_h dω_h = du dφ / 2π), which resolves narrow
    lobes at any α. ``alpha=None``: uniform in μ_o and φ_o (smooth lobes; not
    cosine-weighted, as the sheen lobe holds much of its energy near grazing).
    """
    u, phi, weights = _hemisphere_rule(nodes)
    mu = _MU_NODES[:, None]
    wi = np.stack(np.broadcast_arrays(np.sqrt(1.0 - mu * mu), 0.0, mu), axis=-1)  # (μ, 1, 3)
    if alpha is None:
        s = np.sqrt(1.0 - u * u)
        wo = np.stack([s * np.cos(phi), s * np.sin(phi), u], axis=-1)
        wo = np.broadcast_to(wo, (len(_MU_NODES), *wo.shape))
        integrand_weight = 2.0 * np.pi * wo[..., 2:]  # dω_o = dμ_o dφ
    else:
        tan_h = alpha * np.sqrt(u / (1.0 - u))
        cos_h = 1.0 / np.sqrt(1.0 + tan_h * tan_h)
        sin_h = tan_h * cos_h
        h = np.stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h], axis=-1)
        i_dot_h = np.sum(wi * h, axis=-1, keepdims=True)  # (μ, samples, 1)
        wo = 2.0 * i_dot_h * h - wi
        # f μ_o dω_o = f μ_o · 4 (ω_i·h) dω_h and dω_h = du dφ / (2π D μ_h); the half
        # vector must face ω_i, or the sample belongs to another half vector.
        pdf_h = ggx_d(h[..., 2:], alpha) * h[..., 2:]
        integrand_weight = np.where(i_dot_h > 0, 4.0 * i_dot_h * wo[..., 2:] / pdf_h, 0.0)
    g = geometry(np.broadcast_to(wi, wo.shape), wo)
    f = np.where(g.above, lobe(g), 0.0) * integrand_weight
    values = np.einsum("msc,s->mc", f, weights)
    return Albedo(values=values, average=_cosine_average(values))


def _cosine_average(values: np.ndarray) -> np.ndarray:
    """Ē = 2 ∫₀¹ E(μ) μ dμ of the linear interpolant of ``values`` at ``_MU_NODES``."""
    mu = np.linspace(0.0, 1.0, 4097)
    return np.array([2.0 * np.trapezoid(np.interp(mu, _MU_NODES, column) * mu, mu) for column in values.T])
