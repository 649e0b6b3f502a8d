"""Failure modes of issue 6 (docs/stability.md): renders and look-ups at grazing angles,
and materials with MERL's extreme grazing spikes."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf.data import synth
from frenbrdf.data.folders import mapped_bank, read_tables, split_materials
from frenbrdf.io.merl import CHANNEL_SCALES, SHAPE
from frenbrdf.models import NBRDF, NBRDFConfig
from frenbrdf.models.losses import FrequencyLossConfig, FrequencyTruth
from frenbrdf.models.mapping import LogRelativeMapping, MappingConfig
from frenbrdf.render.renderer import Scene, render, render_linear
from frenbrdf.training import train

from .conftest import tiny, toy_table

# --------------------------------------------------------------------------- grazing angles

#: 89.9° from the view direction (+z), 90° exactly, and along the view.
GRAZING_LIGHTS = (
    (math.sin(math.radians(89.9)), 0.0, math.cos(math.radians(89.9))),
    (0.0, -math.sin(math.radians(89.9)), math.cos(math.radians(89.9))),
    (1.0, 0.0, 0.0),
    (0.0, 0.0, 1.0),
)
#: 256 pixels across put the outermost pixels of the sphere 89.45° from the view.
GRAZING = Scene(resolution=256, light_directions=GRAZING_LIGHTS, light_colors=((1.0, 0.9, 0.8),) * 4,
                environment_samples=0)


def pixel_normals(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals of the sphere's pixels ``(n, n, 3)`` and the mask of pixels on it."""
    c = (np.arange(scene.resolution) + 0.5) / scene.resolution * 2 - 1
    x, y = np.meshgrid(c, -c)
    on_sphere = x * x + y * y < 1
    z = np.sqrt(np.clip(1 - x * x - y * y, 0, None))
    return np.stack([x, y, z], axis=-1), on_sphere


def constant_brdf_image(rgb, scene: Scene) -> np.ndarray:
    """The exact render of a constant BRDF: rgb · Σ_l L_l max(0, n·l) (directional lights only)."""
    normals, on_sphere = pixel_normals(scene)
    lights = np.asarray(scene.light_directions, dtype=np.float64)
    lights /= np.linalg.norm(lights, axis=1, keepdims=True)
    irradiance = np.einsum("hwl,lc->hwc", np.clip(normals @ lights.T, 0, None), np.asarray(scene.light_colors))
    return np.where(on_sphere[..., None], np.asarray(rgb) * irradiance, 0.0)


def constant_table(rgb) -> np.ndarray:
    table = np.broadcast_to(np.asarray(rgb, dtype=np.float64)[:, None, None, None], SHAPE).copy()
    table[:, ~frenbrdf.merl_above_horizon()] = -np.asarray(CHANNEL_SCALES)[:, None]
    return table


def constant_nbrdf(rgb) -> NBRDF:
    """An NBRDF whose network outputs 0 everywhere: reflectance = the per-channel reference."""
    params = [torch.zeros(1, *shape) for shape in NBRDFConfig((8,)).shapes()]
    return NBRDF(params, LogRelativeMapping(np.asarray(rgb, dtype=np.float64)))


def random_nbrdf() -> NBRDF:
    generator = torch.Generator().manual_seed(0)
    params = [torch.randn(1, *shape, generator=generator) * 0.3 for shape in NBRDFConfig((8,)).shapes()]
    return NBRDF(params, LogRelativeMapping(np.full(3, 0.1)))


COATED_SILVER = synth.AnalyticMaterial("coated-silver", metal_n=synth.METALS["silver"][0],
                                       metal_k=synth.METALS["silver"][1], roughness=0.2, coat=1.0,
                                       coat_roughness=0.01)
#: Sheen peaks at grazing angles.
VELVET = synth.AnalyticMaterial("velvet", diffuse=(0.4, 0.1, 0.1), sheen=(1.0, 0.8, 0.8), sheen_roughness=0.3)


def test_the_grazing_scene_reaches_grazing_angles():
    normals, on_sphere = pixel_normals(GRAZING)
    assert np.degrees(np.arccos(normals[on_sphere][:, 2].min())) > 89.4  # silhouette pixels
    lights = np.asarray(GRAZING_LIGHTS)
    cos_i = normals[on_sphere] @ lights.T
    assert 0 < cos_i[cos_i > 0].min() < 0.005  # lights 89.7° from some normals (the terminator)


@pytest.mark.parametrize("source", ["merl-table", "nbrdf", "callable"])
def test_grazing_renders_are_finite_and_non_negative(source):
    brdf = {"merl-table": lambda: synth.merl_table(COATED_SILVER), "nbrdf": random_nbrdf,
            "callable": lambda: lambda wi, wo: synth.evaluate(VELVET, wi, wo)}[source]()
    image = render_linear(brdf, GRAZING)
    assert np.isfinite(image).all() and image.min() >= 0
    normals, on_sphere = pixel_normals(GRAZING)
    silhouette = on_sphere & (normals[..., 2] < math.cos(math.radians(85)))
    assert silhouette.sum() > 100
    assert np.all(image[silhouette].sum(axis=-1) > 0)  # the light along the view reaches them, grazing
    display = render(brdf, GRAZING)
    assert np.isfinite(display).all() and display.min() >= 0 and display.max() <= 1


@pytest.mark.parametrize("source", ["merl-table", "nbrdf", "callable"])
def test_a_constant_brdf_at_grazing_pixels_matches_the_analytic_value(source):
    rgb = np.array([0.1, 0.2, 0.3])
    brdf = {"merl-table": lambda: constant_table(rgb), "nbrdf": lambda: constant_nbrdf(rgb),
            "callable": lambda: lambda wi, wo: np.broadcast_to(rgb, wi.shape)}[source]()
    image = render_linear(brdf, GRAZING)
    expected = constant_brdf_image(rgb, GRAZING)
    normals, on_sphere = pixel_normals(GRAZING)
    lights = np.asarray(GRAZING_LIGHTS)
    cos_i = normals @ (lights / np.linalg.norm(lights, axis=1, keepdims=True)).T
    grazing = on_sphere & ((normals[..., 2] < math.cos(math.radians(85)))
                           | np.any((cos_i > 0) & (cos_i < math.cos(math.radians(85))), axis=-1))
    assert grazing.sum() > 1000
    # The trilinear MERL look-up renormalises over the measured corners: c up to rounding.
    np.testing.assert_allclose(image[grazing], expected[grazing], rtol=1e-12, atol=0)
    np.testing.assert_allclose(image, expected, rtol=1e-12, atol=0)


def spherical(theta_degrees: float, phi: float) -> np.ndarray:
    theta = math.radians(theta_degrees)
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])


def on_the_horizon(phi: float) -> np.ndarray:
    """θ = 90° exactly: z = 0 (``spherical(90, φ)`` has z = 6e-17)."""
    return np.array([math.cos(phi), math.sin(phi), 0.0])


@pytest.mark.parametrize("theta", [89.99, 90.0])
def test_coordinates_and_lookups_at_and_near_the_horizon(theta):
    direction = on_the_horizon if theta == 90.0 else (lambda phi: spherical(theta, phi))
    pairs = [(direction(0.3), spherical(40.0, 2.0)),  # incident grazing
             (spherical(40.0, 2.0), direction(0.3)),  # outgoing grazing
             (direction(0.3), direction(0.3)),  # both, the same direction
             (direction(0.3), direction(0.3 + np.pi)),  # mirror pair; at 90° exactly ω_i = −ω_o
             (direction(0.3), direction(0.3 + np.pi / 2))]
    wi, wo = (np.array(column) for column in zip(*pairs, strict=True))
    angles = frenbrdf.directions_to_rusinkiewicz(wi, wo)
    assert np.isfinite(angles).all()
    assert angles[:, [0, 2]].min() >= 0 and angles[:, [0, 2]].max() <= np.pi / 2 + 1e-15
    wi_back, wo_back = frenbrdf.rusinkiewicz_to_directions(angles)
    np.testing.assert_allclose(wi_back, wi, atol=1e-12)
    np.testing.assert_allclose(wo_back, wo, atol=1e-12)
    h, d = frenbrdf.half_diff_vectors(wi, wo)
    np.testing.assert_allclose(np.linalg.norm(h, axis=1), 1.0, rtol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, rtol=1e-14)

    # A direction on or just above the horizon counts as above it: the trilinear look-up
    # finds measured corners and returns the constant exactly; just below is missing.
    rgb = np.array([0.1, 0.2, 0.3])
    table = constant_table(rgb)
    np.testing.assert_allclose(frenbrdf.merl_lookup_directions(table, wi, wo), np.tile(rgb, (5, 1)), rtol=1e-14)
    nearest = frenbrdf.merl_lookup_directions(table, wi, wo, method="nearest")
    assert np.all((nearest == rgb) | (nearest < 0))  # the nearest bin may be one MERL leaves unmeasured
    below = wi.copy()
    below[:, 2] = -1e-12
    assert np.all(frenbrdf.merl_lookup_directions(table, below, wo) < 0)


def test_the_trilinear_lookup_never_misses_above_the_horizon():
    """Grazing pairs, θ_i, θ_o ∈ [85°, 90°] (90° exactly included), every azimuth difference."""
    rng = np.random.default_rng(0)
    n = 200_000
    theta_i, theta_o = (np.radians(rng.uniform(85, 90, n)) for _ in range(2))
    theta_i[:1000] = theta_o[1000:2000] = np.pi / 2
    phi = rng.uniform(0, 2 * np.pi, n)
    wi = np.stack([np.sin(theta_i), np.zeros(n), np.cos(theta_i)], axis=-1)
    wo = np.stack([np.sin(theta_o) * np.cos(phi), np.sin(theta_o) * np.sin(phi), np.cos(theta_o)], axis=-1)
    wi[:1000, 2] = wo[1000:2000, 2] = 0.0
    rgb = np.array([0.1, 0.2, 0.3])
    np.testing.assert_allclose(frenbrdf.merl_lookup_directions(constant_table(rgb), wi, wo), np.tile(rgb, (n, 1)),
                               rtol=1e-14)


# --------------------------------------------------------------------------- grazing spikes


def grazing_spike_bins() -> tuple[np.ndarray, ...]:
    """Twelve measured bins (θ_h, θ_d, φ_d) with θ_d ≥ 87°, in θ_h slices 0 and 30.

    Slice 0 at θ_d = 89° and φ_d = 0°, 90°: the nodes (90°, 0) and (90°, 90°) of an SHT
    grid with an equator ring take exactly those bins' values (with the mirror extension,
    their images at 91° are as near), so the frequency-loss truth sees the spikes.
    """
    above = frenbrdf.merl_above_horizon()
    fixed = [(0, 89, 0), (0, 89, 90)]
    candidates = np.argwhere(above[[0, 30]][:, 87:, :])
    rng = np.random.default_rng(11)
    chosen = candidates[rng.choice(len(candidates), 10, replace=False)]
    bins = np.array(fixed + [((0, 30)[s], 87 + j, k) for s, j, k in chosen])
    assert above[tuple(bins.T)].all()
    return tuple(bins.T)


@pytest.fixture(scope="module")
def spiky() -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...]]:
    """A Lambert + Blinn–Phong table (and the same without spikes) with 12 grazing bins
    set to 10⁴ … 10⁵, far above the rest, as a few bins near grazing are in measured MERL files."""
    base = toy_table(np.random.default_rng(3))
    table = base.copy()
    bins = grazing_spike_bins()
    spikes = 10 ** np.random.default_rng(4).uniform(4, 5, size=(3, len(bins[0])))
    spikes[:, 0] = 1e5
    for channel in range(3):
        table[channel][bins] = spikes[channel]
    return table, base, bins


def test_spiky_table_round_trips_through_a_merl_file(spiky, tmp_path):
    table, _, bins = spiky
    frenbrdf.write_merl(tmp_path / "spiky.binary", table)
    back = frenbrdf.read_merl(tmp_path / "spiky.binary")
    # Within one rounding of the channel scale (write_merl's documented contract), spikes
    # included; from then on reading and writing are exact inverses.
    np.testing.assert_allclose(back, table, rtol=2.3e-16, atol=0)
    np.testing.assert_allclose(back[:, bins[0], bins[1], bins[2]], table[:, bins[0], bins[1], bins[2]], rtol=2.3e-16)
    assert back[:, bins[0], bins[1], bins[2]].min() > 1e4
    frenbrdf.write_merl(tmp_path / "again.binary", back)
    assert (tmp_path / "again.binary").read_bytes() == (tmp_path / "spiky.binary").read_bytes()
    np.testing.assert_array_equal(frenbrdf.read_merl(tmp_path / "again.binary"), back)


@pytest.fixture(scope="module")
def spiky_folder(spiky, tmp_path_factory):
    """A data folder: the spiky table, its spike-free base and two more toy tables; and
    their reflectance as read back, ``(4, 3, N_BINS)`` with missing bins NaN, in name order."""
    table, base, _ = spiky
    folder = tmp_path_factory.mktemp("spiky-data")
    rng = np.random.default_rng(8)
    for name, t in [("spiky", table), ("toy-0", base), ("toy-1", toy_table(rng)), ("toy-2", toy_table(rng))]:
        frenbrdf.write_merl(folder / f"{name}.binary", t)
    files = sorted(folder.glob("*.binary"))
    assert files[0].stem == "spiky"
    return folder, read_tables(files, progress=False)


@pytest.mark.parametrize("reference", ["per_bin", "per_channel"])
def test_log_mapping_of_spikes_is_finite_and_invertible(spiky, spiky_folder, reference):
    _, _, bins = spiky
    _, tables = spiky_folder
    mapping = LogRelativeMapping.from_tables(tables, MappingConfig(reference=reference))
    assert np.isfinite(mapping.reference).all()
    spiky_table = tables[0]
    valid = ~np.isnan(spiky_table).any(axis=0)
    flat = np.ravel_multi_index(bins, SHAPE[1:])
    mapped = mapping.forward(spiky_table[:, valid], mapping.reference_bins()[:, valid])
    assert np.isfinite(mapped).all()
    spikes = mapping.forward(spiky_table[:, flat], mapping.reference_bins()[:, flat])
    assert spikes.min() > 5  # ln(10⁴ / f_ref) with f_ref ≤ ~50 here: the spikes are there, not clipped
    np.testing.assert_allclose(mapping.inverse(mapped, mapping.reference_bins()[:, valid]), spiky_table[:, valid],
                               rtol=1e-12, atol=1e-15)
    # The bank stores float32: still invertible to float32 precision, spikes included.
    mapped32 = mapped.astype(np.float32).astype(np.float64)
    np.testing.assert_allclose(mapping.inverse(mapped32, mapping.reference_bins()[:, valid]), spiky_table[:, valid],
                               rtol=2e-6, atol=1e-7)

    bank = mapped_bank(["spiky", "toy-0", "toy-1", "toy-2"], tables, mapping)
    assert torch.isfinite(bank.mapped).all()
    np.testing.assert_allclose(bank.mapped[0, flat].numpy().T, spikes, rtol=1e-6)
    batch = bank.sample([0, 1, 0], 100_000, torch.Generator().manual_seed(0))
    for tensor in (batch.coords, batch.values, batch.cos_in):
        assert torch.isfinite(tensor).all()
    assert batch.values.max() <= bank.mapped[0].max()


def test_frequency_truth_of_a_spiky_table_is_finite_and_sees_the_spikes(spiky):
    table, base, bins = spiky
    reference = np.full(3, 0.1)
    mapping = LogRelativeMapping(reference)
    config = FrequencyLossConfig(lmax=12, slices=(0, 30, 60))  # nlat = 13: an equator ring
    truth = FrequencyTruth(config)
    results = {}
    for name, t in (("spiky", table), ("base", base)):
        flat = t.reshape(3, -1)
        valid = np.all(flat >= 0, axis=0)
        mapped = np.where(valid, mapping.forward(np.maximum(flat, 0), reference[:, None]), 0.0).T
        maps = truth.maps(mapped, valid)
        coefficients = truth.coefficients(mapped, valid)
        assert np.isfinite(maps).all() and np.isfinite(coefficients).all()
        # kNN weights are convex: every map stays within its slice's values.
        per_slice = SHAPE[2] * SHAPE[3]
        for s, i in enumerate(config.slices):
            rows = slice(i * per_slice, (i + 1) * per_slice)
            slice_values = mapped[rows][valid[rows]]
            assert maps[s].max() <= slice_values.max() + 1e-12 and maps[s].min() >= slice_values.min() - 1e-12
        results[name] = maps, coefficients
    spike_mapped = mapping.forward(1e5, 0.1)
    assert results["spiky"][0][0].max() == pytest.approx(spike_mapped, rel=1e-12)  # the spike reaches the grid
    assert results["base"][0][0].max() < 5
    assert not np.allclose(results["spiky"][1], results["base"][1])


def test_render_of_a_spiky_table_is_finite(spiky):
    table, base, _ = spiky
    for scene in (GRAZING, Scene(resolution=64)):
        image, without = render_linear(table, scene), render_linear(base, scene)
        assert np.isfinite(image).all() and image.min() >= 0
        assert np.all(image >= without)  # the spikes only add light
        display = render(table, scene)
        assert np.isfinite(display).all() and 0 <= display.min() and display.max() <= 1


def test_training_with_a_spiky_material_stays_finite(spiky, spiky_folder, tmp_path):
    table, _, bins = spiky
    data, _ = spiky_folder
    names = sorted(path.stem for path in data.glob("*.binary"))
    seed = next(seed for seed in range(100) if "spiky" in split_materials(names, seed).train)
    result = train(tiny("frenbrdf", data, tmp_path / "run", epochs=1, seed=seed))
    assert len(result.history) == 2
    assert all(math.isfinite(value) for epoch in result.history for value in epoch.values())
    # Encoding the spiky material (its spikes among the samples) and rendering the decoded NBRDF.
    model = frenbrdf.Model.load(result.path)
    wi, wo = (d.reshape(-1, 3) for d in frenbrdf.merl_bin_directions())
    flat = table.reshape(3, -1).T
    valid = np.flatnonzero(np.all(flat >= 0, axis=1))
    rng = np.random.default_rng(9)
    rows = np.union1d(np.ravel_multi_index(bins, SHAPE[1:]), rng.choice(valid, 20_000))
    z = model.encode(flat[rows], (wi[rows], wo[rows]))
    assert np.isfinite(z).all()
    image = render_linear(model.decode(z), GRAZING)
    assert np.isfinite(image).all() and image.min() >= 0
