"""Isotropic analytic BRDFs: the physically based families behind the synthetic data.

An :class:`AnalyticMaterial` is a base (metal, or Lambert under dielectric specular and
sheen lobes) under an optional clear coat; :func:`evaluate` gives its reflectance at
direction pairs and :func:`merl_table` its MERL table. :mod:`frenbrdf.data.synth` draws
random materials from these families to write the default bank.

Models
------
Directions are unit vectors with the surface normal along +z; ``μ_i = cos θ_i``,
``μ_o = cos θ_o``, ``h = normalize(ω_i + ω_o)``, ``μ_h = cos θ_h`` and
``μ_d = ω_i · h = cos θ_d``. Every lobe is zero unless both directions lie above the
surface.

*Lambert*: ``f = ρ / π``.

*GGX microfacet lobe*: ``f = F(μ_d) · D(μ_h) · G₂(μ_i, μ_o) / (4 μ_i μ_o)`` with the
GGX distribution, height-correlated Smith visibility and exact Fresnel reflectance of
:mod:`frenbrdf.data.microfacet` (formulas and references there). Metals use ``n, k`` per RGB
channel (approximate values of published optical constants at about 650, 550 and
450 nm, :data:`METALS`); dielectrics are the case ``k = 0``.

*Sheen* (Estevez & Kulla 2017, "Production friendly microfacet sheen BRDF", the
"Charlie" distribution, with the visibility term of Neubelt & Pettineo 2013)::

    f = c · (2 + 1/r) sin(θ_h)^(1/r) / (2π) · 1 / (4 (μ_i + μ_o − μ_i μ_o))

*Retro-reflection*: the GGX lobe with ``F = 1`` about the *back* half vector
``normalize(ω_i + ω̄_o)``, ``ω̄_o`` being ``ω_o`` turned by π about the normal, so it peaks at
``ω_o = ω_i``. Turning ``ω_o`` keeps ``μ_o`` and ``dω_o``: the lobe reflects exactly what the
mirror-side lobe of the same α does, and is reciprocal like it.

*Thin film* (:func:`frenbrdf.data.microfacet.thin_film_fresnel`): a dielectric film on the coat replaces the coat's
Fresnel reflectance by Airy's, evaluated per channel at :data:`~frenbrdf.data.microfacet.WAVELENGTHS`: the coat's
colour then shifts with θ_d (iridescence), and stays ≤ 1.

Materials
---------
A material is a *base* under an optional clear *coat*:

- metal base: a GGX conductor lobe times an RGB tint (≤ 1);
- dielectric base: ``w · f_spec + f_sheen + f_retro + ρ/π · (1 − E(μ_i)) (1 − E(μ_o)) / (1 − Ē)``,
  the matte term coupled to the lobe on top of it as in Kelemen & Szirmay-Kalos 2001
  ("A microfacet based coupled specular-matte BRDF model with importance sampling").
  Here ``E(μ)`` is the directional albedo of the top lobes ``w · f_spec + f_sheen + f_retro``
  and ``Ē = 2 ∫ E(μ) μ dμ`` its cosine-weighted average;
- flakes (car paints) cover a share ``s`` of a dielectric base: ``(1 − s) · f_dielectric +
  s · c_flake · f_aluminium``, a mixture of two bases each reflecting at most all light.
  Interference (pearlescent) pigments replace the aluminium by mica flakes under a thin
  high-index film (titanium dioxide): their lobe's Fresnel factor is Airy's, so the colour
  the flakes reflect turns with θ_d, as in colour-shift paints and films. Diffractive
  ("holographic") pigments put a grating of period ``p`` on the aluminium flakes: a share ``η``
  of their light goes into the first orders and ``η/4`` into the second, each a ring where
  ``2 μ_d sin θ_h = m λ / p`` (:func:`~frenbrdf.data.microfacet.ring_density`: the grating
  equation; as wide as the flakes' tilts turn a reflection) integrated over the visible
  spectrum to RGB, the rest stays in the mirror lobe: rainbows about every highlight that
  move out with θ_d. The orders reflect at most ``1.25 η`` of the light (:mod:`~frenbrdf.data.microfacet`
  says why), the mirror lobe at most ``1 − 1.25 η``; the part of an order beyond the horizon
  is absorbed (at normal incidence all of it where ``m λ / p > 1``);
- coat of weight ``c``: ``f = c · f_coat + (1 − c E_c(μ_i)) (1 − c E_c(μ_o)) · f_base``,
  with ``f_coat`` a GGX dielectric lobe (white, or coloured by a thin film) and ``E_c`` its
  directional albedo, the fraction of light the coat reflects (its Fresnel reflectance
  averaged over its microfacets). The base sees the light the coat transmits, on the way
  in and on the way out; directions are not refracted (the "albedo scaling" layering of
  Kulla & Conty 2017, "Revisiting physically based shading at Imageworks").

The directional albedos are tabulated per material on a grid of ``μ`` by a deterministic
quadrature whose half vectors follow the lobe's GGX distribution (so near-mirror lobes are
resolved), and interpolated linearly (:mod:`frenbrdf.data.hemisphere`).

Reciprocity and energy conservation
-----------------------------------
Every lobe is symmetric in ``ω_i, ω_o`` and every coupling factor is a product of the same
function of ``μ_i`` and of ``μ_o``, so every material is reciprocal. The directional
albedo ``A(μ_i) = ∫ f μ_o dω_o`` is at most 1 because:

- a GGX lobe with ``F ≤ 1`` reflects at most its visible normals' share, which is 1
  (``G₂ ≤ G₁``). It models single scattering only: light bouncing between microfacets
  is dropped, so rough lobes are slightly darker than a multiple-scattering model;
- for the dielectric base ``A = E(μ_i) + ρ (1 − E(μ_i)) ≤ 1`` since
  ``∫ (1 − E(μ_o)) μ_o/π dω_o = 1 − Ē`` and ``ρ ≤ 1``; a white base (``ρ = 1``)
  reflects exactly all light. This needs ``E ≤ 1``: true for the specular lobe, and
  for the sheen lobe with ``r ≥ 0.3`` (its albedo peaks at about 0.87, at grazing);
  a material whose top lobes add up to more is refused;
- for the coat ``A = c E_c(μ_i) + (1 − c E_c(μ_i)) ∫ (1 − c E_c(μ_o)) f_base μ_o dω_o
  ≤ c E_c(μ_i) + (1 − c E_c(μ_i)) · 1 = 1`` for any base whose albedo is at most 1.

The tabulated albedos, and with them the energy balance, are accurate to a few 1e-4
(measured: at most about 6e-4 excess, for near-mirror lobes at grazing incidence; 1.1e-3 for
a white base under a near-mirror retro lobe at θ_i = 89°).

Examples
--------
>>> from frenbrdf.data.analytic import METALS, AnalyticMaterial, evaluate, merl_table
>>> gold = AnalyticMaterial("gold", metal_n=METALS["gold"][0], metal_k=METALS["gold"][1], roughness=0.1)
>>> evaluate(gold, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]).shape
(3,)
>>> merl_table(gold).shape                 # −1 × scale where missing
(3, 90, 90, 180)
"""

from __future__ import annotations

import dataclasses
import functools
import re
from dataclasses import dataclass

import numpy as np

from ..io.merl import CHANNEL_SCALES
from .hemisphere import RETRO_QUADRATURE_NODES, Albedo, Geometry, directional_albedo, geometry, merl_geometry
from .microfacet import SPECTRUM, fresnel, ggx_d, ggx_visibility, ring_density, spectrum_rgb, thin_film_fresnel

#: Complex refractive index (n, k) per RGB channel of some metals (the metals of a synthetic bank).
METALS = {
    "gold": ((0.143, 0.374, 1.442), (3.983, 2.385, 1.603)),
    "copper": ((0.200, 0.924, 1.102), (3.912, 2.452, 2.142)),
    "silver": ((0.155, 0.117, 0.138), (4.828, 3.122, 2.147)),
    "aluminium": ((1.657, 0.880, 0.521), (9.224, 6.270, 4.837)),
    "chromium": ((4.369, 2.917, 1.654), (5.206, 4.231, 3.755)),
    "iron": ((2.912, 2.950, 2.585), (3.089, 2.932, 2.767)),
    "brass": ((0.444, 0.527, 1.094), (3.695, 2.765, 1.829)),
}

#: Smallest GGX roughness α accepted: about where the MERL θ_h bins stop resolving the lobe.
MIN_ROUGHNESS = 1e-3
#: Sheen roughness range in which the sheen lobe's albedo stays below 1.
SHEEN_ROUGHNESS_RANGE = (0.3, 1.0)
#: Smallest retro-reflective α: narrower retro peaks fall between the MERL θ_d bins.
RETRO_MIN_ROUGHNESS = 0.05
#: Thin-film thicknesses accepted, in nm: from the first interference colours to where they wash out.
FILM_THICKNESS_RANGE = (50.0, 2000.0)
#: Refractive index of the mica flakes under an interference pigment's film.
MICA_IOR = 1.55
#: Grating periods accepted on diffractive flakes, in nm: from where the first order of red light (700 nm) can
#: still leave the surface, at grazing incidence (p ≥ λ/2), to where the orders crowd into the highlight.
FLAKE_GRATING_RANGE = (350.0, 5000.0)
#: The second orders' share of a grating's light against the first orders' (η and η/4).
SECOND_ORDER_SHARE = 0.25
#: Most of a grating flake's light its orders take (η of the first, η/4 of the second: at most all of it).
MAX_GRATING_EFFICIENCY = 1.0 / (1.0 + SECOND_ORDER_SHARE)
#: Least flake roughness under a grating: the spectrum is sampled every 10 nm, and a ring narrower than the step
#: between neighbouring wavelengths' rings (m · 10 nm / p, at most 0.057 at p = 350 nm) would show them as separate
#: lines; at 0.015 the rings (2α wide) overlap to a rainbow smooth within 1 %.
GRATING_MIN_ROUGHNESS = 0.015

RGB = tuple[float, float, float]


@dataclass(frozen=True)
class AnalyticMaterial:
    """One isotropic analytic BRDF: a base under an optional clear coat.

    The base is a metal when ``metal_n`` is given, otherwise a Lambertian ``diffuse``
    albedo under an optional dielectric specular lobe and an optional sheen lobe. RGB
    values are linear, in [0, 1]. The module docstring gives the formulas.
    """

    name: str
    """Unique, filesystem-safe name (letters, digits, ``.``, ``_``, ``-``)."""
    diffuse: RGB = (0.0, 0.0, 0.0)
    """Lambertian albedo ρ of a dielectric base."""
    specular: float = 0.0
    """Weight of the dielectric GGX specular lobe of a dielectric base (1 = physical)."""
    roughness: float = 0.1
    """GGX α of the base's specular or metal lobe."""
    ior: float = 1.5
    """Refractive index of the base's dielectric specular lobe."""
    metal_n: RGB | None = None
    """Real part of a metal base's complex refractive index, per RGB channel."""
    metal_k: RGB | None = None
    """Imaginary part (extinction coefficient) of a metal base's refractive index."""
    tint: RGB = (1.0, 1.0, 1.0)
    """Multiplies a metal base's lobe (coloured or anodised metals)."""
    sheen: RGB = (0.0, 0.0, 0.0)
    """Colour of the sheen lobe of a dielectric base (fabrics)."""
    sheen_roughness: float = 0.5
    """Roughness r of the sheen lobe, in :data:`SHEEN_ROUGHNESS_RANGE`."""
    coat: float = 0.0
    """Weight of the clear coat, 0 (none) to 1."""
    coat_roughness: float = 0.03
    """GGX α of the coat."""
    coat_ior: float = 1.5
    """Refractive index of the coat."""
    flakes: float = 0.0
    """Share of a dielectric base covered by metallic flakes, 0 (none) to 1 (car paints)."""
    flake_colour: RGB = (1.0, 1.0, 1.0)
    """Multiplies the flakes' aluminium lobe (tinted flakes)."""
    flake_roughness: float = 0.3
    """GGX α of the flakes' orientations."""
    flake_film_thickness: float = 0.0
    """Thickness in nm of a thin film on mica flakes (0: aluminium flakes): interference pigments."""
    flake_film_ior: float = 2.5
    """Refractive index of the film on the flakes (titanium dioxide: about 2.5)."""
    flake_grating: float = 0.0
    """Period in nm of a grating on aluminium flakes (0: none): diffractive pigments."""
    flake_grating_efficiency: float = 0.3
    """Share η of the grating flakes' light diffracted into the first orders (η/4 more into the second)."""
    retro: RGB = (0.0, 0.0, 0.0)
    """Weight per channel of a dielectric base's retro-reflective lobe (0: none)."""
    retro_roughness: float = 0.3
    """GGX α of the retro-reflective lobe."""
    film_thickness: float = 0.0
    """Thickness in nm of a thin dielectric film on the coat (0: none): an iridescent coat."""
    film_ior: float = 1.33
    """Refractive index of the film on the coat."""

    def __post_init__(self):
        if not re.fullmatch(r"[A-Za-z0-9._-]+", self.name):
            raise ValueError(f"material name must be non-empty and use only letters, digits, '.', '_', '-': "
                             f"{self.name!r}")
        for field in ("diffuse", "tint", "sheen", "flake_colour", "retro"):
            object.__setattr__(self, field, _rgb(field, getattr(self, field), 0.0, 1.0))
        if (self.metal_n is None) != (self.metal_k is None):
            raise ValueError(f"{self.name}: give both metal_n and metal_k, or neither")
        if self.metal_n is not None:
            object.__setattr__(self, "metal_n", _rgb("metal_n", self.metal_n, 1e-3, 100.0))
            object.__setattr__(self, "metal_k", _rgb("metal_k", self.metal_k, 0.0, 100.0))
            if any(self.diffuse) or self.specular or any(self.sheen) or self.flakes or any(self.retro):
                raise ValueError(f"{self.name}: a metal base has no diffuse, specular, sheen, flake or retro lobe")
        if self.film_thickness and not self.coat:
            raise ValueError(f"{self.name}: a thin film lies on the coat; give coat > 0")
        _check_range(self.name, "specular", self.specular, 0.0, 1.0)
        _check_range(self.name, "coat", self.coat, 0.0, 1.0)
        _check_range(self.name, "roughness", self.roughness, MIN_ROUGHNESS, 1.0)
        _check_range(self.name, "coat_roughness", self.coat_roughness, MIN_ROUGHNESS, 1.0)
        _check_range(self.name, "sheen_roughness", self.sheen_roughness, *SHEEN_ROUGHNESS_RANGE)
        _check_range(self.name, "ior", self.ior, 1.0, 3.0)
        _check_range(self.name, "coat_ior", self.coat_ior, 1.0, 3.0)
        _check_range(self.name, "flakes", self.flakes, 0.0, 1.0)
        _check_range(self.name, "flake_roughness", self.flake_roughness, MIN_ROUGHNESS, 1.0)
        _check_range(self.name, "retro_roughness", self.retro_roughness, RETRO_MIN_ROUGHNESS, 1.0)
        _check_range(self.name, "film_ior", self.film_ior, 1.0, 3.0)
        _check_range(self.name, "flake_film_ior", self.flake_film_ior, 1.0, 3.0)
        for field in ("film_thickness", "flake_film_thickness"):
            if getattr(self, field):
                _check_range(self.name, field, getattr(self, field), *FILM_THICKNESS_RANGE)
        if self.flake_film_thickness and not self.flakes:
            raise ValueError(f"{self.name}: a flake film lies on flakes; give flakes > 0")
        if self.flake_grating:
            _check_range(self.name, "flake_grating", self.flake_grating, *FLAKE_GRATING_RANGE)
            if not self.flakes or self.flake_film_thickness:
                raise ValueError(f"{self.name}: a grating lies on aluminium flakes; give flakes > 0 and no flake film")
            _check_range(self.name, "flake_roughness under a grating", self.flake_roughness, GRATING_MIN_ROUGHNESS,
                         1.0)
        _check_range(self.name, "flake_grating_efficiency", self.flake_grating_efficiency, 0.0,
                     MAX_GRATING_EFFICIENCY)

    @property
    def kind(self) -> str:
        """The feature that names the material, the first that applies of ``"iridescent"``
        (thin film), ``"diffractive"`` (grating flakes), ``"pearlescent"`` (interference flakes),
        ``"carpaint"`` (flakes), ``"coated"``,
        ``"metal"``, ``"retroreflective"``, ``"fabric"`` (sheen), ``"plastic"`` and ``"diffuse"``."""
        if self.film_thickness:
            return "iridescent"
        if self.flake_grating:
            return "diffractive"
        if self.flake_film_thickness:
            return "pearlescent"
        if self.flakes:
            return "carpaint"
        if self.coat > 0:
            return "coated"
        if self.metal_n is not None:
            return "metal"
        if any(self.retro):
            return "retroreflective"
        if any(self.sheen):
            return "fabric"
        if self.specular > 0:
            return "plastic"
        return "diffuse"

    def to_dict(self) -> dict:
        """The fields and the kind, as JSON-ready values."""
        return {"kind": self.kind, **dataclasses.asdict(self)}


def _rgb(field: str, value, low: float, high: float) -> RGB:
    rgb = tuple(float(v) for v in np.asarray(value, dtype=np.float64).reshape(-1))
    if len(rgb) != 3 or not all(low <= v <= high for v in rgb):
        raise ValueError(f"{field} must be 3 values in [{low}, {high}], got {value!r}")
    return rgb


def _check_range(name: str, field: str, value: float, low: float, high: float) -> None:
    if not low <= value <= high:
        raise ValueError(f"{name}: {field} must lie in [{low}, {high}], got {value!r}")


# --- Lobes ---------------------------------------------------------------------------


def _facets(g: Geometry, alpha: float, cos_h: np.ndarray | None = None) -> np.ndarray:
    """D · G₂ / (4 μ_i μ_o): a GGX lobe without its Fresnel factor, about the half vector whose
    cosine is ``cos_h`` (default: the ordinary one, ``g.cos_h``)."""
    return ggx_d(g.cos_h if cos_h is None else cos_h, alpha) * ggx_visibility(g.cos_i, g.cos_o, alpha)


def _ggx_lobe(g: Geometry, alpha: float, n, k) -> np.ndarray:
    """F · D · G₂ / (4 μ_i μ_o) for a GGX interface of index ``n + i k``."""
    return fresnel(g.cos_d, n, k) * _facets(g, alpha)


def _sheen_lobe(g: Geometry, r: float) -> np.ndarray:
    """Charlie sheen distribution with Neubelt & Pettineo's visibility (white)."""
    sin_h = np.sqrt(np.maximum(1.0 - g.cos_h * g.cos_h, 0.0))
    d = (2.0 + 1.0 / r) * sin_h ** (1.0 / r) / (2.0 * np.pi)
    return d / (4.0 * (g.cos_i + g.cos_o - g.cos_i * g.cos_o))


def _retro_lobe(g: Geometry, alpha: float) -> np.ndarray:
    """A white (F = 1) GGX lobe about the back half vector: it peaks at ``ω_o = ω_i``.

    Turning ``ω_o`` by π about the normal keeps ``μ_o`` and ``dω_o``, so it reflects exactly what
    ``_facets(g, alpha)``, its mirror-side twin, does: the albedo tables integrate that one.
    """
    return _facets(g, alpha, g.cos_back)


def _metal_lobe(m: AnalyticMaterial, g: Geometry) -> np.ndarray:
    return np.asarray(m.tint) * _ggx_lobe(g, m.roughness, m.metal_n, m.metal_k)


def _flake_lobe(m: AnalyticMaterial, g: Geometry) -> np.ndarray:
    """Tinted flakes whose orientations spread as a GGX distribution: aluminium, aluminium under a grating, or mica
    under a thin film."""
    if m.flake_grating:
        orders = (1.0 + SECOND_ORDER_SHARE) * m.flake_grating_efficiency
        mirror = (1.0 - orders) * _ggx_lobe(g, m.flake_roughness, *METALS["aluminium"])
        return np.asarray(m.flake_colour) * (mirror + _grating_orders(m, g))
    if not m.flake_film_thickness:
        return np.asarray(m.flake_colour) * _ggx_lobe(g, m.flake_roughness, *METALS["aluminium"])
    film = thin_film_fresnel(g.cos_d, m.flake_film_ior, m.flake_film_thickness, MICA_IOR)
    return np.asarray(m.flake_colour) * film * _facets(g, m.flake_roughness)


def _grating_orders(m: AnalyticMaterial, g: Geometry) -> np.ndarray:
    """The grating flakes' first and second orders: per order and wavelength a ring in the plane of the directions'
    tangential parts (:func:`~frenbrdf.data.microfacet.ring_density`), as wide as the flakes' tilts turn a
    reflection (2α), weighted to RGB over the spectrum, with aluminium's Fresnel reflectance. The part of a ring
    that lies beyond the horizon (tangential parts outside the unit disk: at normal incidence the whole order where
    ``m λ / p > 1``) is absorbed, not handed back to the mirror lobe: a fine grating darkens its flakes there."""
    rho = 2.0 * g.cos_d * np.sqrt(np.maximum(1.0 - g.cos_h * g.cos_h, 0.0))  # |ω_i,t + ω_o,t|
    rings = 0.0
    for order, efficiency in ((1, m.flake_grating_efficiency), (2, SECOND_ORDER_SHARE * m.flake_grating_efficiency)):
        for wavelength, rgb in zip(SPECTRUM, spectrum_rgb(), strict=True):
            rings = rings + efficiency * rgb * ring_density(rho, order * wavelength / m.flake_grating,
                                                             2.0 * m.flake_roughness)
    return rings * fresnel(g.cos_d, *METALS["aluminium"])


def _top_lobes(m: AnalyticMaterial, g: Geometry) -> np.ndarray | float:
    """The lobes above a dielectric base's matte term whose albedo is tabulated together:
    specular (white) and sheen (RGB), 0 without them. The retro lobe is tabulated on its own."""
    f: np.ndarray | float = 0.0
    if m.specular > 0:
        f = f + m.specular * _ggx_lobe(g, m.roughness, m.ior, 0.0)
    if any(m.sheen):
        f = f + np.asarray(m.sheen) * _sheen_lobe(g, m.sheen_roughness)
    return f


def _coat_lobe(m: AnalyticMaterial, g: Geometry) -> np.ndarray:
    if not m.film_thickness:
        return _ggx_lobe(g, m.coat_roughness, m.coat_ior, 0.0)
    return thin_film_fresnel(g.cos_d, m.film_ior, m.film_thickness, m.coat_ior) * _facets(g, m.coat_roughness)


@dataclass(frozen=True)
class _Albedos:
    top: Albedo | None  # the dielectric base's specular, sheen and retro lobes
    coat: Albedo | None


@functools.lru_cache(maxsize=256)
def _albedos(m: AnalyticMaterial) -> _Albedos:
    """The directional albedo tables a material needs (cached: materials are immutable)."""
    top = None
    if m.metal_n is None and (m.specular > 0 or any(m.sheen)):
        alpha = m.roughness if m.specular > 0 else None  # follow the narrower lobe
        top = directional_albedo(lambda g: _top_lobes(m, g), alpha)
    if any(m.retro):
        retro = directional_albedo(lambda g: np.asarray(m.retro) * _facets(g, m.retro_roughness), m.retro_roughness,
                                   RETRO_QUADRATURE_NODES)  # the retro lobe's mirror-side twin (_retro_lobe)
        top = retro if top is None else top + retro
    if top is not None and top.values.max() > 1.0:
        raise ValueError(f"{m.name}: the specular, sheen and retro lobes together reflect more light than "
                         f"arrives (albedo {top.values.max():.3f}); lower specular, sheen or retro")
    coat = directional_albedo(lambda g: _coat_lobe(m, g), m.coat_roughness) if m.coat > 0 else None
    return _Albedos(top=top, coat=coat)


# --- Evaluation ----------------------------------------------------------------------


def _dielectric_base(m: AnalyticMaterial, g: Geometry, albedos: _Albedos) -> np.ndarray:
    matte = np.asarray(m.diffuse) / np.pi
    if albedos.top is None:
        return matte
    # Kelemen & Szirmay-Kalos coupling: the matte term gets what the top lobes leave.
    e = albedos.top
    coupling = (1.0 - e(g.cos_i)) * (1.0 - e(g.cos_o))
    top = _top_lobes(m, g)
    if any(m.retro):
        top = top + np.asarray(m.retro) * _retro_lobe(g, m.retro_roughness)
    return top + coupling * (matte / (1.0 - e.average))


def _base(m: AnalyticMaterial, g: Geometry, albedos: _Albedos) -> np.ndarray:
    if m.metal_n is not None:
        return _metal_lobe(m, g)
    f = _dielectric_base(m, g, albedos)
    if m.flakes:  # a mixture: flakes cover a share of the surface, the paint the rest
        f = (1.0 - m.flakes) * f + m.flakes * _flake_lobe(m, g)
    return f


def _evaluate(m: AnalyticMaterial, g: Geometry) -> np.ndarray:
    albedos = _albedos(m)
    f = _base(m, g, albedos)
    if albedos.coat is not None:  # m.coat > 0
        transmitted_in = 1.0 - m.coat * albedos.coat(g.cos_i)
        transmitted_out = 1.0 - m.coat * albedos.coat(g.cos_o)
        f = m.coat * _coat_lobe(m, g) + transmitted_in * transmitted_out * f
    return np.where(g.above, f, 0.0)


def evaluate(material: AnalyticMaterial, wi, wo) -> np.ndarray:
    """Evaluates a material's BRDF at direction pairs.

    Parameters
    ----------
    material
        The material.
    wi, wo
        Directions ``(..., 3)``, broadcast against each other; the surface normal is +z.
        They are normalised here.

    Returns
    -------
    numpy.ndarray
        RGB reflectance (1/sr), float64 ``(..., 3)``: finite, ≥ 0, reciprocal, and 0
        where either direction is at or below the horizon.
    """
    wi, wo = np.broadcast_arrays(np.asarray(wi, dtype=np.float64), np.asarray(wo, dtype=np.float64))
    if wi.ndim == 0 or wi.shape[-1] != 3:
        raise ValueError(f"wi and wo must have shape (..., 3), got {np.shape(wi)}")
    return _evaluate(material, geometry(wi, wo))


def merl_table(material: AnalyticMaterial) -> np.ndarray:
    """The material as a MERL table, in physical units.

    Bins are evaluated at their own angles (φ_h = 0). Bins where a direction is below
    the horizon (:func:`frenbrdf.io.merl.merl_above_horizon` is False) hold MERL's missing
    marker: stored value −1, i.e. ``-CHANNEL_SCALES[c]`` here.

    Returns
    -------
    numpy.ndarray
        float64 ``(3, 90, 90, 180)``.
    """
    g = merl_geometry()
    table = np.moveaxis(_evaluate(material, g), -1, 0).copy()
    table[:, ~g.above[..., 0]] = -np.asarray(CHANNEL_SCALES)[:, None]
    return table

