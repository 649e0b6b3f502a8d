"""GGX microfacet terms and exact Fresnel reflectance, shared by the analytic BRDFs and the renderers.

Directions are unit vectors with the surface normal along +z; ``μ_i = cos θ_i``,
``μ_o = cos θ_o``, ``μ_h = cos θ_h`` of the half vector and ``μ_d = cos θ_d``.

*GGX microfacet lobe* (Walter, Marschner, Li & Torrance 2007, "Microfacet models for
refraction through rough surfaces"; the distribution is Trowbridge & Reitz's)::

    f = F(μ_d) · D(μ_h) · G₂(μ_i, μ_o) / (4 μ_i μ_o)
    D = α² / (π (1 + μ_h² (α² − 1))²)                                   (ggx_d)
    G₂ / (4 μ_i μ_o) = 1 / (2 (μ_o √(α² + μ_i² (1 − α²)) + μ_i √(α² + μ_o² (1 − α²))))   (ggx_visibility)

with the height-correlated Smith masking-shadowing G₂ = 1 / (1 + Λ(μ_i) + Λ(μ_o)) (Heitz
2014, "Understanding the masking-shadowing function in microfacet-based BRDFs").

*Fresnel reflectance* ``F`` (:func:`fresnel`) is the exact unpolarised one of a smooth
interface from air into a medium of complex refractive index ``n + i k`` (Born & Wolf,
"Principles of Optics"), written in real arithmetic: with ``s² = 1 − μ²``,
``t = n² − k² − s²``, ``a² + b² = √(t² + 4 n² k²)`` and ``a = √((a² + b² + t) / 2)``::

    R_s = (a² + b² − 2 a μ + μ²) / (a² + b² + 2 a μ + μ²)
    R_p = R_s (μ² (a² + b²) − 2 a μ s² + s⁴) / (μ² (a² + b²) + 2 a μ s² + s⁴)
    F   = (R_s + R_p) / 2

Dielectrics are the case ``k = 0``.

*Grating rings* (:func:`ring_density`): a grating of period ``p`` on flakes parallel to the surface sends order
``m`` of wavelength ``λ`` where the tangential parts of ``ω_i`` and ``ω_o`` add up to ``m λ / p`` (the grating
equation), that is where ``ρ = |ω_i,t + ω_o,t| = 2 μ_d sin θ_h = m λ / p``. A flake's grating lies at any angle in
its plane, so each order of each wavelength is a ring in the plane of tangential parts, blurred by the flakes'
tilts: rainbows about every highlight that move out as θ_d grows (diffractive, "holographic" pigments). As
``μ_o dω_o`` is the area element of that plane, ``f = η F(μ_d) R(ρ)`` with ``R`` a density on the plane
(``∫ R d²u = 1``) reflects ``η F`` times the part of the ring inside the unit disk: at most ``η``.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.special import erf

#: Wavelengths (nm) at which the RGB channels evaluate a thin film (as the metals' ``n, k`` of
#: :data:`frenbrdf.data.analytic.METALS` are given).
WAVELENGTHS = (650.0, 550.0, 450.0)

#: Wavelengths (nm) over which a diffracting lobe is integrated (:func:`spectrum_rgb`).
SPECTRUM = tuple(float(w) for w in range(400, 701, 10))


def fresnel(cos: np.ndarray, n, k) -> np.ndarray:
    """Exact unpolarised Fresnel reflectance from air into index ``n + i k`` (broadcast)."""
    n, k = np.asarray(n, dtype=np.float64), np.asarray(k, dtype=np.float64)
    cos2 = cos * cos
    sin2 = 1.0 - cos2
    t = n * n - k * k - sin2
    a2b2 = np.sqrt(t * t + 4.0 * n * n * k * k)
    a = np.sqrt(np.maximum(0.5 * (a2b2 + t), 0.0))
    r_s = (a2b2 - 2.0 * a * cos + cos2) / (a2b2 + 2.0 * a * cos + cos2)
    r_p = r_s * (cos2 * a2b2 - 2.0 * a * cos * sin2 + sin2 * sin2) / (cos2 * a2b2 + 2.0 * a * cos * sin2 + sin2 * sin2)
    return 0.5 * (r_s + r_p)


def ggx_d(cos_h: np.ndarray, alpha: float) -> np.ndarray:
    """GGX (Trowbridge–Reitz) normal distribution D(θ_h)."""
    a2 = alpha * alpha
    t = 1.0 + cos_h * cos_h * (a2 - 1.0)
    return a2 / (np.pi * t * t)


def ggx_visibility(cos_i: np.ndarray, cos_o: np.ndarray, alpha: float) -> np.ndarray:
    """Height-correlated Smith G₂ / (4 μ_i μ_o) for GGX."""
    a2 = alpha * alpha
    masking_i = cos_o * np.sqrt(a2 + cos_i * cos_i * (1.0 - a2))  # μ_i μ_o (1 + 2 Λ(μ_i))
    masking_o = cos_i * np.sqrt(a2 + cos_o * cos_o * (1.0 - a2))
    return 0.5 / (masking_i + masking_o)


def thin_film_fresnel(cos: np.ndarray, film_ior: float, thickness: float, substrate_ior: float) -> np.ndarray:
    """Unpolarised reflectance of a thin dielectric film on a dielectric substrate, from air.

    Airy's sum of the film's multiple reflections (Born & Wolf, "Principles of Optics",
    §1.6) at the :data:`WAVELENGTHS`, per polarisation, with real amplitudes ``r₁₂, r₂₃``
    and the phase ``δ = 4π n₂ d cos θ₂ / λ``::

        R = (r₁₂² + r₂₃² + 2 r₁₂ r₂₃ cos δ) / (1 + r₁₂² r₂₃² + 2 r₁₂ r₂₃ cos δ)

    which is at most 1 for lossless layers, and equals the bare substrate's Fresnel
    reflectance as ``thickness → 0``. ``cos`` is ``(..., 1)``, the result ``(..., 3)``.
    """
    sin2 = 1.0 - cos * cos
    cos_film = np.sqrt(1.0 - sin2 / film_ior**2)
    cos_sub = np.sqrt(1.0 - sin2 / substrate_ior**2)
    delta = 4.0 * np.pi * film_ior * thickness * cos_film / np.asarray(WAVELENGTHS)
    n1, n2, n3 = 1.0, film_ior, substrate_ior
    amplitudes = (((n1 * cos - n2 * cos_film) / (n1 * cos + n2 * cos_film),  # s
                   (n2 * cos_film - n3 * cos_sub) / (n2 * cos_film + n3 * cos_sub)),
                  ((n2 * cos - n1 * cos_film) / (n2 * cos + n1 * cos_film),  # p
                   (n3 * cos_film - n2 * cos_sub) / (n3 * cos_film + n2 * cos_sub)))
    polarised = []
    for r12, r23 in amplitudes:
        cross = 2.0 * r12 * r23 * np.cos(delta)
        polarised.append((r12**2 + r23**2 + cross) / (1.0 + (r12 * r23) ** 2 + cross))
    return 0.5 * (polarised[0] + polarised[1])


def ring_density(rho: np.ndarray, radius: float | np.ndarray, width: float) -> np.ndarray:
    """A density on the plane, ``∫ R d²u = 1``, on a ring: Gaussian in the distance ``rho`` from the origin about
    ``radius`` with standard deviation ``width``."""
    # 2π ∫₀^∞ exp(−(ρ − r)² / 2w²) ρ dρ, in closed form.
    w2 = width * width
    mass = 2.0 * np.pi * (w2 * np.exp(-radius * radius / (2.0 * w2))
                          + radius * width * np.sqrt(np.pi / 2.0) * (1.0 + erf(radius / (width * np.sqrt(2.0)))))
    return np.exp(-(rho - radius) ** 2 / (2.0 * w2)) / mass


def cie_xyz(wavelengths: np.ndarray) -> np.ndarray:
    """The CIE 1931 2° colour matching functions x̄, ȳ, z̄ at ``wavelengths`` (nm), ``(..., 3)``: the multi-lobe
    analytic fit of Wyman, Sloan & Shirley 2013 ("Simple analytic approximations to the CIE XYZ color matching
    functions")."""

    def lobe(mean, left, right):
        return np.exp(-0.5 * ((wavelengths - mean) / np.where(wavelengths < mean, left, right)) ** 2)

    return np.stack([1.056 * lobe(599.8, 37.9, 31.0) + 0.362 * lobe(442.0, 16.0, 26.7) - 0.065 * lobe(501.1, 20.4, 26.2),
                     0.821 * lobe(568.8, 46.9, 40.5) + 0.286 * lobe(530.9, 16.3, 31.1),
                     1.217 * lobe(437.0, 11.8, 36.0) + 0.681 * lobe(459.0, 26.0, 13.8)], axis=-1)


@functools.cache
def spectrum_rgb() -> np.ndarray:
    """Linear sRGB weights ``(len(SPECTRUM), 3)`` of each wavelength of :data:`SPECTRUM`, each channel summing to 1
    (an equal-energy spectrum is white): the CIE 1931 matching functions (:func:`cie_xyz`) to sRGB (D65) with
    what falls outside its gamut clipped to 0."""
    xyz = cie_xyz(np.array(SPECTRUM))
    to_srgb = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])
    rgb = np.maximum(xyz @ to_srgb.T, 0.0)
    weights = rgb / rgb.sum(axis=0)
    weights.flags.writeable = False  # cached: one array for every caller
    return weights
