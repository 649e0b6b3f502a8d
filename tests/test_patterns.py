"""Sampling patterns (frenbrdf.io.patterns): each gives exactly the pairs it documents, and a whole material is
measured at them (read_samples, reconstruct, evaluate take a pattern)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import frenbrdf
from frenbrdf.io.merl import N_BINS, SHAPE, merl_lookup_directions
from frenbrdf.io.patterns import INCIDENCE, PATTERNS, measure, pattern_samples, sample_pattern
from frenbrdf.io.samples import MAX_SAMPLES
from frenbrdf.io.sampling import bin_directions, draw_samples, sample_bins
from frenbrdf.numerics.coords import directions_to_rusinkiewicz

from .conftest import toy_table
from .io.test_bsdf_native import flat_material, tensor_file


def _angles(wi, wo) -> tuple[np.ndarray, ...]:
    """θ_h, φ_h, θ_d, φ_d of each pair."""
    return tuple(directions_to_rusinkiewicz(wi, wo).T)


@pytest.mark.parametrize("name", PATTERNS)
@pytest.mark.parametrize("count", [1, 7, 1500])
def test_every_pattern_gives_exactly_count_unit_pairs_above_the_horizon(name, count):
    wi, wo = sample_pattern(name, count, np.random.default_rng(3))
    for w in (wi, wo):
        assert w.shape == (count, 3) and w.dtype == np.float64
        np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1, atol=1e-12)
        assert (w[:, 2] > 0).all()


@pytest.mark.parametrize("name", PATTERNS)
def test_a_pattern_is_the_same_from_the_same_seed_and_not_from_another(name):
    first, again, other = (sample_pattern(name, 400, np.random.default_rng(seed)) for seed in (5, 5, 6))
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.allclose(first[1], other[1])


def test_merl_bins_are_the_bins_reconstruct_has_always_drawn():
    wi, wo = sample_pattern("merl-bins", 300, np.random.default_rng(1))
    full = np.ones(SHAPE)  # every bin measured: the bins above the horizon
    expected = bin_directions(sample_bins(full, np.random.default_rng(1), 300))
    np.testing.assert_array_equal(wi, expected[0])
    np.testing.assert_array_equal(wo, expected[1])
    assert np.allclose(_angles(wi, wo)[1], 0, atol=1e-9)  # φ_h = 0, as MERL's bins


def test_uniform_and_cosine_weight_the_hemisphere_as_documented():
    rng = np.random.default_rng(0)
    for name, mean_cos in (("uniform", 1 / 2), ("cosine", 2 / 3)):  # E[cos θ] by solid angle and cosine-weighted
        wi, wo = sample_pattern(name, 20_000, rng)
        assert wi[:, 2].mean() == pytest.approx(mean_cos, abs=0.01)
        assert wo[:, 2].mean() == pytest.approx(mean_cos, abs=0.01)
        assert abs(np.corrcoef(wi[:, 2], wo[:, 2])[0, 1]) < 0.03  # independent


def test_in_plane_pairs_share_the_plane_of_incidence():
    wi, wo = sample_pattern("in-plane", 2000, np.random.default_rng(0))
    np.testing.assert_allclose(wi[:, 0] * wo[:, 1] - wi[:, 1] * wo[:, 0], 0, atol=1e-12)  # φ_o − φ_i is 0 or π
    folded = np.mod(_angles(wi, wo)[3], np.pi)  # and so φ_d is 0 or π
    assert np.all(np.minimum(folded, np.pi - folded) < 1e-6)
    assert (np.degrees(np.arccos(wi[:, 2])) <= 85 + 1e-9).all()


def test_the_gonioreflectometer_has_a_few_incidence_angles_and_sweeps_mostly_in_plane():
    wi, wo = sample_pattern("gonioreflectometer", 3000, np.random.default_rng(0))
    theta_i = np.arccos(wi[:, 2])
    nearest = np.abs(theta_i[:, None] - np.array(INCIDENCE)[None]).min(axis=1)
    assert (nearest <= math.radians(0.25) + 1e-9).all()  # only the k angles, up to the ±0.25° jitter
    counts = np.bincount(np.abs(theta_i[:, None] - np.array(INCIDENCE)[None]).argmin(axis=1))
    assert counts.tolist() == [600] * len(INCIDENCE)  # the count spread evenly
    out_of_plane = np.abs(wi[:, 0] * wo[:, 1] - wi[:, 1] * wo[:, 0]) / np.maximum(np.hypot(wi[:, 0], wi[:, 1]), 1e-9)
    near_plane = out_of_plane < math.sin(math.radians(0.5))  # normal incidence has no plane: it counts as in it
    assert 0.65 <= near_plane.mean() <= 0.85
    assert (out_of_plane > math.sin(math.radians(20))).sum() > 300  # the arcs across the plane


@pytest.mark.parametrize("lights", [1, 3, 8])
def test_image_based_gives_one_theta_d_per_light(lights):
    wi, wo = sample_pattern("image-based", 1000, np.random.default_rng(lights))
    theta_h, _, theta_d, _ = _angles(wi, wo)
    assert len(np.unique(np.round(theta_d, 7))) <= 8  # a light's θ_d is the same at every pixel
    from frenbrdf.io.patterns import image_based

    wi, wo = image_based(900, np.random.default_rng(0), lights=lights)
    theta_h, _, theta_d, _ = _angles(wi, wo)
    assert len(np.unique(np.round(theta_d, 7))) == lights
    assert theta_d.max() <= math.radians(135) / 2 + 1e-9 and theta_h.min() < math.radians(10)


def test_a_flat_sample_gives_a_small_patch_per_light_with_the_highlight_in_the_first():
    from frenbrdf.io.patterns import flat_sample

    for seed in range(5):
        wi, wo = flat_sample(500, np.random.default_rng(seed), lights=1)
        theta_h, _, theta_d, _ = _angles(wi, wo)
        assert np.ptp(theta_d) < math.radians(15) and theta_h.min() < math.radians(25)


def test_the_peak_patterns_stay_at_their_peaks():
    rng = np.random.default_rng(0)
    theta_h, _, theta_d, _ = _angles(*sample_pattern("specular", 3000, rng))
    assert theta_h.max() <= math.radians(20) + 1e-9 and np.ptp(theta_d) > math.radians(70)
    theta_h, _, theta_d, _ = _angles(*sample_pattern("back-scatter", 3000, rng))
    assert theta_d.max() <= math.radians(20) + 1e-9 and np.ptp(theta_h) > math.radians(70)
    theta_h, _, theta_d, _ = _angles(*sample_pattern("peaks", 3001, rng))
    specular, back = theta_h <= math.radians(20) + 1e-9, theta_d <= math.radians(20) + 1e-9
    assert (specular | back).all() and specular.sum() >= 1500 and back.sum() >= 1500


def test_unknown_names_and_bad_counts_are_refused():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="unknown sampling pattern 'goniometer'; the patterns are merl-bins, "):
        sample_pattern("goniometer", 100, rng)
    for count in (0, -5, MAX_SAMPLES + 1, 1.5, True, "100"):
        with pytest.raises(ValueError, match=r"count must be a whole number in 1 … 4,000,000 \(devices give 50 …"):
            sample_pattern("uniform", count, rng)
    assert sample_pattern("uniform", np.int64(3), rng)[0].shape == (3, 3)


def test_a_table_is_looked_up_at_the_pairs_and_merl_bins_is_todays_sampling():
    table = toy_table(np.random.default_rng(0))
    measured = measure(table, "gonioreflectometer", 500, np.random.default_rng(2), source="toy.binary")
    assert len(measured) == 500 and measured.kind == "merl" and measured.truth is table
    np.testing.assert_array_equal(measured.values, merl_lookup_directions(table, measured.wi, measured.wo))
    again = measure(table, "gonioreflectometer", 500, np.random.default_rng(2))
    np.testing.assert_array_equal(measured.values, again.values)
    today = draw_samples(table, samples=400, seed=9)
    bins = measure(table, "merl-bins", 400, np.random.default_rng(9))
    for field in ("values", "wi", "wo"):
        np.testing.assert_array_equal(getattr(bins, field), getattr(today, field))


def test_unmeasured_bins_are_drawn_again_and_a_table_with_none_where_a_pattern_looks_is_named():
    table = toy_table(np.random.default_rng(0))
    table[:, 60:] = -1  # θ_h above 40°: not measured
    values, (wi, wo) = pattern_samples(table, "uniform", 800, np.random.default_rng(0))
    assert values.shape == (800, 3) and (values >= 0).all() and len(wi) == len(wo) == 800
    table[:, :60] = -1  # nothing measured below θ_h = 40°, where the specular pattern samples
    with pytest.raises(ValueError, match="toy.binary: the table holds a measurement at 0 of 100 pairs drawn by "
                       "'specular'"):
        measure(table, "specular", 100, np.random.default_rng(0), source="toy.binary")


def test_read_samples_takes_a_pattern_for_a_whole_material(tmp_path):
    path = tmp_path / "toy.binary"
    frenbrdf.write_merl(path, toy_table(np.random.default_rng(1)))
    drawn = frenbrdf.read_samples(path, samples=300, seed=4, pattern="in-plane")
    assert len(drawn) == 300 and drawn.kind == "merl" and drawn.table is not None
    np.testing.assert_allclose(drawn.wi[:, 0] * drawn.wo[:, 1] - drawn.wi[:, 1] * drawn.wo[:, 0], 0, atol=1e-12)
    default = frenbrdf.read_samples(path, samples=300, seed=4)
    np.testing.assert_array_equal(default.values, draw_samples(drawn.table, samples=300, seed=4).values)
    with pytest.raises(ValueError, match="unknown sampling pattern 'dense'"):
        frenbrdf.read_samples(path, pattern="dense")
    with pytest.raises(ValueError, match="samples=None .* the merl-bins pattern only, not 'uniform'"):
        frenbrdf.read_samples(path, samples=None, pattern="uniform")
    assert len(frenbrdf.read_samples(path, samples=None)) <= N_BINS


def test_a_measurement_is_evaluated_at_the_pairs_in_the_patterns_order(tmp_path):
    path = tmp_path / "flat.bsdf"
    path.write_bytes(tensor_file(flat_material()))
    measurement = frenbrdf.read_material(path)
    drawn = frenbrdf.read_samples(path, samples=200, seed=0, pattern="image-based")
    assert drawn.kind == "bsdf" and drawn.truth is not None and drawn.table is not None
    np.testing.assert_array_equal(drawn.values, np.maximum(measurement(drawn.wi, drawn.wo), 0))
