"""The synthetic material bank: determinism, physics of the analytic BRDFs, MERL files."""

from __future__ import annotations

import colorsys
import dataclasses
import itertools
import json
import re
from collections import Counter

import numpy as np
import pytest

import frenbrdf
from frenbrdf.data import synth
from frenbrdf.data.analytic import (
    FILM_THICKNESS_RANGE,
    FLAKE_GRATING_RANGE,
    GRATING_MIN_ROUGHNESS,
    MAX_GRATING_EFFICIENCY,
)
from frenbrdf.data.microfacet import SPECTRUM, cie_xyz, fresnel, ring_density, spectrum_rgb, thin_film_fresnel
from frenbrdf.data.synth import (
    DIFFRACTIVE_SHARES,
    FAMILY_SHARES,
    FEATURE_SHARES,
    KIND_SHARES,
    KINDS,
    METALS,
    AnalyticMaterial,
)
from frenbrdf.io.merl import CHANNEL_SCALES, SHAPE
from frenbrdf.io.outputs import MARKER

from .conftest import unit_vectors

SILVER, GOLD = METALS["silver"], METALS["gold"]
WHITE = (1.0, 1.0, 1.0)

#: Hand-made materials at the edges of the parameter ranges, one or more per kind.
EXTREMES = {
    "white-lambert": AnalyticMaterial("white-lambert", diffuse=WHITE),
    "white-mirror-plastic": AnalyticMaterial("white-mirror-plastic", diffuse=WHITE, specular=1.0, roughness=0.01,
                                             ior=1.7),
    "white-rough-plastic": AnalyticMaterial("white-rough-plastic", diffuse=WHITE, specular=1.0, roughness=0.6,
                                            ior=1.7),
    "mirror-silver": AnalyticMaterial("mirror-silver", metal_n=SILVER[0], metal_k=SILVER[1], roughness=0.01),
    "rough-gold": AnalyticMaterial("rough-gold", metal_n=GOLD[0], metal_k=GOLD[1], roughness=0.6),
    "white-fabric": AnalyticMaterial("white-fabric", diffuse=WHITE, sheen=WHITE, sheen_roughness=0.3),
    "coated-white": AnalyticMaterial("coated-white", diffuse=WHITE, coat=1.0, coat_roughness=0.01, coat_ior=1.6),
    "coated-silver": AnalyticMaterial("coated-silver", metal_n=SILVER[0], metal_k=SILVER[1], roughness=0.2,
                                      coat=1.0, coat_roughness=0.1),
    "white-retro": AnalyticMaterial("white-retro", diffuse=WHITE, retro=(0.4, 0.4, 0.4), retro_roughness=0.05,
                                    specular=1.0, roughness=0.3),
    "white-flakes": AnalyticMaterial("white-flakes", diffuse=WHITE, flakes=1.0, flake_roughness=0.05, coat=1.0,
                                     coat_roughness=0.01),
    "thick-film": AnalyticMaterial("thick-film", diffuse=(0.02, 0.02, 0.02), coat=1.0, coat_roughness=0.01,
                                   film_thickness=FILM_THICKNESS_RANGE[1], film_ior=2.5),
    "white-pearl-flakes": AnalyticMaterial("white-pearl-flakes", diffuse=WHITE, flakes=1.0, flake_roughness=0.05,
                                           flake_film_thickness=FILM_THICKNESS_RANGE[0], flake_film_ior=3.0,
                                           coat=1.0, coat_roughness=0.01),
    # the finest grating and the sharpest flakes: the orders take the most light, at the widest angles
    "white-grating-flakes": AnalyticMaterial("white-grating-flakes", diffuse=WHITE, flakes=1.0, flake_roughness=0.02,
                                             flake_grating=FLAKE_GRATING_RANGE[0],
                                             flake_grating_efficiency=MAX_GRATING_EFFICIENCY, coat=1.0,
                                             coat_roughness=0.01),
}
#: White dielectric bases are energy-preserving: they reflect all the light they receive.
PRESERVING = ("white-lambert", "white-mirror-plastic", "white-rough-plastic", "white-fabric", "white-retro")


@pytest.fixture(scope="module")
def bank() -> list[AnalyticMaterial]:
    return synth.material_bank(100, seed=0)


@pytest.fixture(scope="module")
def features() -> list[AnalyticMaterial]:
    return synth.material_bank(60, seed=1, mix="features")


@pytest.fixture(scope="module")
def families() -> list[AnalyticMaterial]:
    return synth.material_bank(45, seed=0, mix="families")


@pytest.fixture(scope="module")
def diffractive() -> list[AnalyticMaterial]:
    return synth.material_bank(15, seed=0, mix="diffractive")


@pytest.fixture(scope="module")
def one_of_each_kind(bank, features, families, diffractive) -> dict[str, AnalyticMaterial]:
    """A material of every kind any mix draws (names end in the kind drawn: a glitter is a "carpaint")."""
    return {kind: next(m for m in bank + features + families + diffractive if m.name.endswith(f"-{kind}"))
            for kind in {*KINDS, *FEATURE_SHARES, *FAMILY_SHARES, *DIFFRACTIVE_SHARES}}


def directional_albedo(material: AnalyticMaterial, theta_i: float, n: int = 128) -> np.ndarray:
    """∫ f cos θ_o dω_o by deterministic multiple importance sampling, RGB.

    Strategies: cosine-weighted and uniform directions (the latter for lobes that peak at
    grazing, such as sheen), and one GGX half-vector density per roughness
    the material has (so mirror-like lobes are resolved; the retro lobe's about ω_i),
    each on an n × n grid of stratum midpoints, combined with the balance heuristic.
    """
    wi = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])
    alphas = [material.roughness] if material.metal_n is not None or material.specular > 0 else []
    alphas += [material.coat_roughness] if material.coat > 0 else []
    alphas += [material.flake_roughness] if material.flakes > 0 else []
    retro_alphas = [material.retro_roughness] if any(material.retro) else []
    turn = np.array([-1.0, -1.0, 1.0])  # by π about the normal
    u1, u2 = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n, indexing="ij")
    u1, phi = u1.reshape(-1), 2 * np.pi * u2.reshape(-1)

    def ggx_d(cos_h, alpha):
        return alpha**2 / (np.pi * (1 + cos_h**2 * (alpha**2 - 1)) ** 2)

    samples = [np.stack([np.sqrt(u1) * np.cos(phi), np.sqrt(u1) * np.sin(phi), np.sqrt(1 - u1)], axis=-1),
               np.stack([np.sqrt(1 - u1**2) * np.cos(phi), np.sqrt(1 - u1**2) * np.sin(phi), u1], axis=-1)]
    for alpha, turned in [(a, False) for a in alphas] + [(a, True) for a in retro_alphas]:
        cos_h = 1 / np.sqrt(1 + alpha**2 * u1 / (1 - u1))
        sin_h = np.sqrt(1 - cos_h**2)
        h = np.stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h], axis=-1)
        mirrored = 2 * (h @ wi)[:, None] * h - wi
        samples.append(mirrored * turn if turned else mirrored)
    wo = np.concatenate(samples)
    wo = wo[wo[:, 2] > 0]

    def ggx_pdf(wo, alpha):
        h = wi + wo
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        return np.where(h @ wi > 0, ggx_d(h[:, 2], alpha) * h[:, 2] / (4 * np.abs(h @ wi)), 0.0)

    ggx_pdfs = [ggx_pdf(wo, a) for a in alphas] + [ggx_pdf(wo * turn, a) for a in retro_alphas]
    pdfs = wo[:, 2] / np.pi + 1 / (2 * np.pi) + sum(ggx_pdfs)
    f = synth.evaluate(material, wi, wo)
    return np.sum(f * (wo[:, 2] / pdfs)[:, None], axis=0) / n**2


def fresnel_complex(cos, n, k):
    """Unpolarised Fresnel reflectance from air into n + ik, in complex arithmetic."""
    eta = n + 1j * k
    cos_t = np.sqrt(1 - (1 - cos**2) / eta**2 + 0j)
    r_s = (cos - eta * cos_t) / (cos + eta * cos_t)
    r_p = (eta * cos - cos_t) / (eta * cos + cos_t)
    return 0.5 * (np.abs(r_s) ** 2 + np.abs(r_p) ** 2)


# --- The bank ------------------------------------------------------------------------


def test_the_same_seed_gives_the_same_bank_and_tables():
    first, second = synth.material_bank(12, seed=3), synth.material_bank(12, seed=3)
    assert first == second
    np.testing.assert_array_equal(synth.merl_table(first[0]), synth.merl_table(second[0]))

    other = synth.material_bank(12, seed=4)
    assert [m.to_dict() for m in other] != [m.to_dict() for m in first]
    assert not np.array_equal(synth.merl_table(other[0]), synth.merl_table(first[0]))


def test_a_bank_of_100_holds_every_kind_in_its_share(bank):
    assert len(bank) == 100
    assert Counter(m.kind for m in bank) == {kind: round(100 * share) for kind, share in KIND_SHARES.items()}
    names = [m.name for m in bank]
    assert len(set(names)) == 100
    assert all(re.fullmatch(r"synth-\d{3}-[a-z-]+-(" + "|".join(KINDS) + ")", name) for name in names)
    assert [int(name.split("-")[1]) for name in names] == list(range(100))
    changes = sum(a.kind != b.kind for a, b in itertools.pairwise(bank))
    assert changes > 50  # shuffled, not grouped by kind


def test_bank_parameters_lie_in_physical_ranges(bank):
    metals = set(METALS.values())
    for m in bank:
        if m.kind in ("plastic", "metal"):
            assert 0.01 <= m.roughness <= 0.6
        if m.metal_n is not None:
            assert (m.metal_n, m.metal_k) in metals
            assert max(m.tint) == pytest.approx(1.0) and min(m.tint) > 0.2
        if m.kind == "plastic":
            assert m.specular == 1.0 and 1.4 <= m.ior <= 1.7
        if m.kind == "coated":
            assert 0.6 <= m.coat <= 1 and 0.01 <= m.coat_roughness <= 0.15
        assert max(m.diffuse) <= 0.9
    # Colours spread like paints: some dark, some bright, moderately saturated on average.
    albedos = np.array([m.diffuse for m in bank if any(m.diffuse)])
    assert np.sum(albedos.max(axis=1) < 0.08) >= 5 and np.sum(albedos.max(axis=1) > 0.5) >= 10
    saturation = 1 - albedos.min(axis=1) ** (1 / 2.2) / albedos.max(axis=1) ** (1 / 2.2)
    assert 0.25 < saturation.mean() < 0.6
    roughness = np.array([m.roughness for m in bank if m.kind in ("plastic", "metal")])
    assert roughness.min() < 0.03 and roughness.max() > 0.3
    assert len({m.metal_n for m in bank if m.kind == "metal"}) >= 5


def test_the_families_mix_holds_its_three_kinds_as_their_physics_says(families):
    assert Counter(m.name.rsplit("-", 1)[1] for m in families) == {"iridescent": 15, "pearlescent": 15, "glitter": 15}
    pearls = [m for m in families if m.kind == "pearlescent"]
    assert all(m.flake_film_thickness > 0 and m.flakes > 0 and m.coat > 0 for m in pearls)
    # glitter: sparkles of a hue at least a fifth of a turn from the base's
    for m in (m for m in families if m.name.endswith("-glitter")):
        base, sparkle = (colorsys.rgb_to_hsv(*(c ** (1 / 2.2) for c in rgb))[0] for rgb in (m.diffuse, m.flake_colour))
        assert min(abs(base - sparkle), 1 - abs(base - sparkle)) > 0.19, m.name


def test_pearlescent_flakes_turn_their_colour_with_the_angle():
    """The flakes' interference colour at the mirror direction changes from normal to grazing incidence."""
    pearl = AnalyticMaterial("pearl", diffuse=(0.02, 0.02, 0.02), flakes=1.0, flake_roughness=0.1,
                             flake_film_thickness=400.0)
    chromaticities = []
    for theta in np.radians([5.0, 45.0, 70.0]):
        wi = np.array([np.sin(theta), 0.0, np.cos(theta)])
        f = synth.evaluate(pearl, wi, wi * [-1, -1, 1])
        chromaticities.append(f / f.sum())
    assert np.ptp(np.array(chromaticities), axis=0).max() > 0.05
    with pytest.raises(ValueError, match="flake film lies on flakes"):
        AnalyticMaterial("bad", diffuse=WHITE, flake_film_thickness=400.0)


def test_the_features_mix_holds_its_kinds_in_their_shares(features):
    assert Counter(m.kind for m in features) == {kind: round(60 * share) for kind, share in FEATURE_SHARES.items()}
    assert all(m.name.startswith("features-") for m in features)
    assert not {m.name for m in features} & {m.name for m in synth.material_bank(100)}  # can share a folder
    with pytest.raises(ValueError, match="mix must be one of"):
        synth.material_bank(5, mix="measured")


@pytest.mark.parametrize("n", [5, 6, 7, 11])
def test_small_banks_still_hold_every_kind(n):
    bank = synth.material_bank(n, seed=1)
    assert len(bank) == n and {m.kind for m in bank} == set(KINDS)


@pytest.mark.parametrize("n", [1, 2, 4])
def test_tiny_banks_hold_n_materials(n):
    assert len(synth.material_bank(n)) == n


def test_a_bank_needs_one_material(tmp_path):
    with pytest.raises(ValueError, match="holds 1 … 10,000 materials"):
        synth.material_bank(0)
    with pytest.raises(ValueError, match="holds 1 … 10,000 materials"):
        synth.write_bank(tmp_path / "bank", n=0, progress=False)
    assert not (tmp_path / "bank").exists()


@pytest.mark.parametrize(
    "fields",
    [
        {"name": "a/b"},
        {"name": "x", "diffuse": (1.2, 0, 0)},
        {"name": "x", "roughness": 0.0},
        {"name": "x", "sheen": WHITE, "sheen_roughness": 0.1},
        {"name": "x", "metal_n": SILVER[0]},
        {"name": "x", "metal_n": SILVER[0], "metal_k": SILVER[1], "diffuse": (0.5, 0.5, 0.5)},
    ],
)
def test_unphysical_materials_are_refused(fields):
    with pytest.raises(ValueError):
        AnalyticMaterial(**fields)


def test_top_lobes_that_reflect_more_than_all_light_are_refused():
    too_bright = AnalyticMaterial("x", specular=1.0, roughness=0.3, sheen=WHITE, sheen_roughness=0.3)
    with pytest.raises(ValueError, match="more light"):
        synth.evaluate(too_bright, [0, 0, 1], [0, 0, 1])
    too_retro = AnalyticMaterial("y", specular=1.0, roughness=0.3, retro=WHITE, retro_roughness=0.3)
    with pytest.raises(ValueError, match="more light"):
        synth.evaluate(too_retro, [0, 0, 1], [0, 0, 1])


@pytest.mark.parametrize(
    ("fields", "named"),
    [
        ({"retro": (0.1, 0.1, 0.1), "retro_roughness": 0.01}, "retro_roughness"),  # finer than MERL bins resolve
        ({"flakes": 1.5}, "flakes"),
        ({"film_thickness": 300.0}, "film lies on the coat"),
        ({"film_thickness": 10.0, "coat": 1.0}, "film_thickness"),
        ({"metal_n": SILVER[0], "metal_k": SILVER[1], "flakes": 0.5}, "metal"),
        ({"flake_grating": 800.0}, "grating lies on aluminium flakes"),
        ({"flakes": 0.5, "flake_grating": 100.0}, "flake_grating"),  # no visible order would leave the surface
        ({"flakes": 0.5, "flake_grating": 800.0, "flake_film_thickness": 300.0}, "grating lies on aluminium flakes"),
        ({"flakes": 0.5, "flake_grating": 800.0, "flake_grating_efficiency": 0.9}, "flake_grating_efficiency"),
        ({"flakes": 0.5, "flake_grating": 800.0, "flake_roughness": 0.01}, "flake_roughness under a grating"),
    ],
)
def test_unphysical_feature_lobes_are_refused(fields, named):
    with pytest.raises(ValueError, match=named):
        AnalyticMaterial("x", **fields)


# --- Physics of the BRDFs ------------------------------------------------------------


def every_material(one_of_each_kind):
    return [*one_of_each_kind.values(), *EXTREMES.values()]


def test_evaluate_is_reciprocal_finite_non_negative_and_zero_below_the_horizon(one_of_each_kind):
    rng = np.random.default_rng(5)
    wi, wo = unit_vectors(rng, 5000), unit_vectors(rng, 5000)
    wo[:50] = -wi[:50]  # ω_i = −ω_o: no half vector
    wo[50:100] = wi[50:100] * [-1, -1, 1]  # mirror configurations: the lobe peaks
    for material in every_material(one_of_each_kind):
        f = synth.evaluate(material, wi, wo)
        assert f.shape == (5000, 3)
        assert np.all(np.isfinite(f)) and np.all(f >= 0), material.name
        np.testing.assert_allclose(f, synth.evaluate(material, wo, wi), rtol=1e-12, atol=0, err_msg=material.name)
        below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
        assert np.all(f[below] == 0) and np.all(f[~below].max(axis=1) > 0), material.name


def test_evaluate_broadcasts_directions():
    material = EXTREMES["rough-gold"]
    wo = unit_vectors(np.random.default_rng(0), 12).reshape(3, 4, 3)
    f = synth.evaluate(material, [0.0, 0.0, 1.0], wo)
    assert f.shape == (3, 4, 3)
    np.testing.assert_allclose(f, synth.evaluate(material, np.broadcast_to([0.0, 0.0, 1.0], wo.shape), wo))


THETA_I = np.radians([0.0, 30.0, 60.0, 80.0, 89.0])


def test_no_material_reflects_more_light_than_it_receives(one_of_each_kind):
    for material in every_material(one_of_each_kind):
        for theta in THETA_I:
            albedo = directional_albedo(material, theta)
            assert np.all(albedo <= 1 + 2e-3), (material.name, np.degrees(theta), albedo)
            assert np.all(albedo > 0), material.name


@pytest.mark.parametrize("name", PRESERVING)
def test_white_dielectric_bases_reflect_all_light(name):
    # The coupled matte term receives exactly what the lobes above it do not reflect.
    for theta in THETA_I:
        np.testing.assert_allclose(directional_albedo(EXTREMES[name], theta), 1.0, atol=3e-3,
                                   err_msg=f"{name} at θ_i = {np.degrees(theta):.0f}°")


def test_the_albedo_estimator_is_exact_for_lambert():
    material = AnalyticMaterial("grey", diffuse=(0.2, 0.5, 0.8))
    for theta in THETA_I:
        np.testing.assert_allclose(directional_albedo(material, theta), [0.2, 0.5, 0.8], rtol=1e-3)


def test_a_coat_brightens_the_highlight_and_dims_the_rest():
    base = AnalyticMaterial("base", diffuse=(0.5, 0.3, 0.1))
    coated = dataclasses.replace(base, name="coated", coat=1.0, coat_roughness=0.05)
    wi = np.array([np.sin(0.5), 0.0, np.cos(0.5)])
    mirror, off_mirror = wi * [-1, -1, 1], np.array([0.6, 0.0, 0.8])
    assert np.all(synth.evaluate(coated, wi, mirror) > 10 * synth.evaluate(base, wi, mirror))
    ratio = synth.evaluate(coated, wi, off_mirror) / synth.evaluate(base, wi, off_mirror)
    assert np.all((0.85 < ratio) & (ratio < 0.97))  # about (1 − 0.05)² transmitted, in and out


def test_the_retro_lobe_peaks_back_towards_the_light():
    material = AnalyticMaterial("retro", diffuse=(0.2, 0.2, 0.2), retro=(0.3, 0.3, 0.3), retro_roughness=0.1)
    for theta in np.radians([20.0, 45.0, 70.0]):
        wi = np.array([np.sin(theta), 0.0, np.cos(theta)])
        back, mirror = synth.evaluate(material, wi, wi), synth.evaluate(material, wi, wi * [-1, -1, 1])
        assert np.all(back > 5 * mirror), np.degrees(theta)


def test_a_thin_film_tends_to_the_bare_coat_and_shifts_colour_with_angle():
    cos = np.linspace(0.01, 1.0, 50)[:, None]
    np.testing.assert_allclose(thin_film_fresnel(cos, 1.8, 1e-6, 1.5), np.broadcast_to(fresnel(cos, 1.5, 0.0), (50, 3)),
                               rtol=1e-9)
    for thickness in (50.0, 300.0, 900.0, 2000.0):
        for film_ior in (1.2, 1.8, 2.5):
            r = thin_film_fresnel(cos, film_ior, thickness, 1.5)
            assert np.all((r >= 0) & (r <= 1)), (thickness, film_ior)
    # A quarter-wave film of index √1.5 on glass is an anti-reflection coat for its wavelength (green).
    r = thin_film_fresnel(np.array([[1.0]]), np.sqrt(1.5), 550.0 / (4 * np.sqrt(1.5)), 1.5)[0]
    assert r[1] < 1e-12 and r[0] > 1e-4 and r[2] > 1e-4
    normal, oblique = thin_film_fresnel(np.array([[1.0], [0.5]]), 1.8, 400.0, 1.5)
    assert np.abs(normal / normal.sum() - oblique / oblique.sum()).max() > 0.05  # iridescence


def test_grating_rings_hold_the_plane_and_the_spectrum_turns_white_light_white():
    rho = np.linspace(0.0, 6.0, 600_001)
    for radius, width in ((0.0, 0.05), (0.5, 0.04), (1.5, 0.3)):
        mass = np.trapezoid(2 * np.pi * rho * ring_density(rho, radius, width), rho)
        assert mass == pytest.approx(1.0, abs=1e-6), (radius, width)
    # The fit against the CIE 1931 table: x̄(600), ȳ(555), ȳ(500), z̄(450), x̄(450).
    xyz = cie_xyz(np.array([600.0, 555.0, 500.0, 450.0, 450.0]))
    np.testing.assert_allclose(xyz[[0, 1, 2, 3, 4], [0, 1, 1, 2, 0]], [1.0622, 1.0000, 0.3230, 1.7721, 0.3362],
                               rtol=0.04)
    weights = spectrum_rgb()
    np.testing.assert_allclose(weights.sum(axis=0), 1.0)
    assert np.all(weights >= 0)
    peaks = np.array(SPECTRUM)[weights.argmax(axis=0)]  # red, green, blue: long, middle, short wavelengths
    assert peaks[2] < 480 < peaks[1] < 580 < peaks[0]


def test_a_grating_on_flakes_puts_rainbows_where_the_grating_equation_says():
    """Each order lies where 2 μ_d sin θ_h = m λ / p, so its rings stay put in ρ = 2 μ_d sin θ_h, moving out in θ_h
    as θ_d grows; red lies outside blue (dispersion); the orders take at most 1.25 η of the light."""
    period, efficiency = 1000.0, 0.5
    flakes = AnalyticMaterial("holo", diffuse=(0.0, 0.0, 0.0), flakes=1.0, flake_roughness=GRATING_MIN_ROUGHNESS,
                              flake_grating=period, flake_grating_efficiency=efficiency)
    for theta_d in np.radians([10.0, 40.0]):
        theta_h = np.radians(np.linspace(8.0, 25.0, 2001))  # beyond the mirror lobe's tail
        half = np.stack([np.sin(theta_h), np.zeros_like(theta_h), np.cos(theta_h)], axis=-1)
        # ω_i and ω_o at θ_d either side of the half vector, in the plane perpendicular to the one of θ_h
        side = np.array([0.0, np.sin(theta_d), 0.0])
        wi, wo = half * np.cos(theta_d) + side, half * np.cos(theta_d) - side
        f = synth.evaluate(flakes, wi, wo)
        rho = 2 * np.cos(theta_d) * np.sin(theta_h[f.argmax(axis=0)])  # where each channel's first order peaks
        blue_wavelength, red_wavelength = (SPECTRUM[i] for i in spectrum_rgb()[:, [2, 0]].argmax(axis=0))
        assert rho[2] == pytest.approx(blue_wavelength / period, abs=0.03), np.degrees(theta_d)
        assert rho[0] == pytest.approx(red_wavelength / period, abs=0.03), np.degrees(theta_d)
    for theta in np.radians([0.0, 45.0, 80.0]):
        orders = directional_albedo(flakes, theta)
        mirror_only = directional_albedo(dataclasses.replace(flakes, flake_grating_efficiency=0.0), theta)
        assert np.all(orders - (1 - 1.25 * efficiency) * mirror_only <= 1.25 * efficiency + 1e-3), theta


def test_the_finest_grating_at_its_least_roughness_gives_a_smooth_rainbow_not_lines():
    """The spectrum is sampled every 10 nm: at the least roughness a grating allows, the finest grating's first
    order still shows one band per channel (green, whose weights have one lobe), not a line per wavelength."""
    flakes = AnalyticMaterial("holo", diffuse=(0.0, 0.0, 0.0), flakes=1.0, flake_roughness=GRATING_MIN_ROUGHNESS,
                              flake_grating=FLAKE_GRATING_RANGE[0], flake_grating_efficiency=0.5)
    theta_d = np.radians(10.0)
    theta_h = np.radians(np.linspace(20.0, 89.0, 4001))  # ρ from 0.67 to 1.97: the first order (1.14 to 2)
    half = np.stack([np.sin(theta_h), np.zeros_like(theta_h), np.cos(theta_h)], axis=-1)
    side = np.array([0.0, np.sin(theta_d), 0.0])
    green = synth.evaluate(flakes, half * np.cos(theta_d) + side, half * np.cos(theta_d) - side)[:, 1]
    steps = np.diff(green)
    slopes = np.sign(steps[np.abs(steps) > 1e-6 * green.max()])  # rising +1, falling −1, flat parts left out
    peaks = np.count_nonzero((slopes[:-1] > 0) & (slopes[1:] < 0))
    assert peaks == 1, peaks  # at 0.005, a third of the least roughness, 13


def test_the_diffractive_mix_holds_grating_flakes_of_real_pigments(diffractive):
    assert {m.kind for m in diffractive} == {"diffractive"}
    assert all(500.0 <= m.flake_grating <= 2000.0 and m.coat > 0 for m in diffractive)  # 500–2,000 lines/mm


def test_car_paint_flakes_tint_the_highlight_around_a_white_coat_glint():
    paint = AnalyticMaterial("paint", diffuse=(0.3, 0.1, 0.01), flakes=0.4, flake_colour=(1.0, 0.8, 0.1),
                             flake_roughness=0.2, coat=1.0, coat_roughness=0.01)
    theta = np.radians(30.0)
    wi = np.array([np.sin(theta), 0.0, np.cos(theta)])
    glint = synth.evaluate(paint, wi, wi * [-1, -1, 1])
    turned = np.radians(-30.0 - 12.0)  # 12° off the mirror: outside the coat's lobe, inside the flakes'
    sparkle = synth.evaluate(paint, wi, np.array([np.sin(turned), 0.0, np.cos(turned)]))
    assert glint.min() / glint.max() > 0.9  # the coat reflects white
    assert sparkle[1] / sparkle[0] > 0.6 and sparkle[2] / sparkle[0] < 0.2  # the flakes yellow


def test_metal_reflectance_follows_the_exact_conductor_fresnel():
    # In the mirror configuration (θ_h = 0) the lobe is F(θ_d) · D(0) · V(θ_d, θ_d).
    n, k = GOLD
    alpha = 0.2
    material = AnalyticMaterial("gold", metal_n=n, metal_k=k, roughness=alpha)
    theta_d = np.radians(np.linspace(0, 89, 60))
    cos = np.cos(theta_d)[:, None]
    wi = np.stack([np.sin(theta_d), 0 * theta_d, np.cos(theta_d)], axis=-1)
    f = synth.evaluate(material, wi, wi * [-1, -1, 1])
    d_peak = 1 / (np.pi * alpha**2)
    visibility = 0.5 / (2 * cos * np.sqrt(alpha**2 + cos**2 * (1 - alpha**2)))
    expected = fresnel_complex(cos, np.array(n), np.array(k))
    np.testing.assert_allclose(f / (d_peak * visibility), expected, rtol=1e-10)


# --- MERL tables ---------------------------------------------------------------------


def test_tables_mark_missing_bins_as_merl_does(tmp_path, one_of_each_kind):
    table = synth.merl_table(one_of_each_kind["metal"])
    above = frenbrdf.merl_above_horizon()
    assert table.shape == SHAPE and table.dtype == np.float64
    np.testing.assert_array_equal(frenbrdf.valid_mask(table), above)
    assert np.all(np.isfinite(table[:, above])) and np.all(table[:, above] >= 0)

    path = tmp_path / "metal.binary"
    frenbrdf.write_merl(path, table)
    stored = frenbrdf.read_merl(path, physical_units=False)
    assert np.all(stored[:, ~above] == -1.0)
    assert np.all(stored[:, above] >= 0)
    np.testing.assert_array_equal(table[:, ~above], -np.broadcast_to(np.array(CHANNEL_SCALES)[:, None],
                                                                      (3, int((~above).sum()))))


def test_tables_hold_the_brdf_at_the_bin_directions(one_of_each_kind):
    rng = np.random.default_rng(2)
    bins = np.stack([rng.integers(0, 90, 3000), rng.integers(0, 90, 3000), rng.integers(0, 180, 3000)], axis=-1)
    angles = frenbrdf.merl_bin_to_angles(bins)
    wi, wo = frenbrdf.rusinkiewicz_to_directions(np.stack([angles[:, 0], 0 * angles[:, 0], angles[:, 1],
                                                           angles[:, 2]], axis=-1))
    valid = frenbrdf.merl_above_horizon()[tuple(bins.T)]
    assert 0.5 < valid.mean() < 0.95
    for material in one_of_each_kind.values():
        table = synth.merl_table(material)
        from_table = table[:, bins[:, 0], bins[:, 1], bins[:, 2]].T
        np.testing.assert_allclose(from_table[valid], synth.evaluate(material, wi, wo)[valid], rtol=1e-9,
                                   err_msg=material.name)
        assert np.all(np.isfinite(table)) and np.all(table[:, frenbrdf.merl_above_horizon()] >= 0)


def test_a_lambert_table_is_albedo_over_pi():
    albedo = np.array([0.7, 0.2, 0.05])
    table = synth.merl_table(AnalyticMaterial("paint", diffuse=albedo))
    above = frenbrdf.merl_above_horizon()
    np.testing.assert_allclose(table[:, above], np.broadcast_to((albedo / np.pi)[:, None], (3, int(above.sum()))),
                               rtol=1e-15)


def test_a_metal_table_starts_at_its_fresnel_f0():
    # At θ_h = θ_d = 0 both directions are the normal: f = F0 · tint / (4π α²).
    n, k = np.array(METALS["copper"])
    tint, alpha = (1.0, 0.8, 0.6), 0.1
    table = synth.merl_table(AnalyticMaterial("copper", metal_n=n, metal_k=k, tint=tint, roughness=alpha))
    f0 = ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)
    np.testing.assert_allclose(table[:, 0, 0, 0] * 4 * np.pi * alpha**2, f0 * tint, rtol=1e-12)
    assert f0[0] > f0[1] > f0[2]  # copper is red


def test_a_rougher_lobe_has_a_lower_peak_and_wider_tail():
    def slice_at(alpha):  # θ_d = 30°, φ_d = 90°, along θ_h
        n, k = METALS["aluminium"]
        return synth.merl_table(AnalyticMaterial("al", metal_n=n, metal_k=k, roughness=alpha))[1, :, 30, 90]

    smooth, rough = slice_at(0.05), slice_at(0.4)
    assert smooth[0] > 10 * rough[0]
    assert rough[60] > 10 * smooth[60]
    assert np.all(np.diff(smooth[:60]) < 0)  # GGX falls off monotonically away from the peak


# --- Writing a bank ------------------------------------------------------------------


def test_write_bank_writes_merl_files_and_a_manifest(tmp_path):
    out = tmp_path / "new" / "bank"
    paths = synth.write_bank(out, n=3, seed=7, progress=False)
    bank = synth.material_bank(3, seed=7)
    assert paths == [out / f"{m.name}.binary" for m in bank]
    assert sorted(p.name for p in out.iterdir() if p.name != MARKER) == sorted([*(p.name for p in paths), synth.MANIFEST_NAME])
    for path, material in zip(paths, bank, strict=True):
        assert path.stat().st_size == frenbrdf.io.merl.FILE_BYTES
        np.testing.assert_allclose(frenbrdf.read_merl(path), synth.merl_table(material), rtol=1e-15)

    manifest = json.loads((out / synth.MANIFEST_NAME).read_text())
    assert manifest["n"] == 3 and manifest["seed"] == 7
    assert [entry["file"] for entry in manifest["materials"]] == [p.name for p in paths]
    field_names = {field.name for field in dataclasses.fields(AnalyticMaterial)}
    for entry, material in zip(manifest["materials"], bank, strict=True):
        assert entry["kind"] == material.kind
        assert AnalyticMaterial(**{key: entry[key] for key in field_names}) == material
