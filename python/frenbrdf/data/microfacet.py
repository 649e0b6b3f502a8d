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
"""

from __future__ import annotations

import numpy as np

#: Wavelengths (nm) at which the RGB channels evaluate a thin film (as the metals' ``n, k`` of
#: :data:`frenbrdf.data.analytic.METALS` are given).
WAVELENGTHS = (650.0, 550.0, 450.0)


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
