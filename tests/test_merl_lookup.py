"""Bin ↔ angle maps and table lookups at arbitrary angles and direction pairs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import frenbrdf
from frenbrdf.io.merl import SHAPE

HALF_PI = np.pi / 2


def merl_reference_bins(theta_h, theta_d, phi_d):
    """MERL's reference reader (BRDFRead.cpp), ported to numpy: floor of the index."""
    h = np.clip(np.floor(np.sqrt(theta_h / HALF_PI * 90 * 90)), 0, 89)
    d = np.clip(np.floor(theta_d / HALF_PI * 90), 0, 89)
    phi = np.where(phi_d < 0, phi_d + np.pi, phi_d)
    p = np.clip(np.floor(phi / np.pi * 180), 0, 179)
    return np.stack([h, d, p], axis=-1).astype(np.int64)


def test_bin_angles_follow_the_merl_axes():
    theta_h, theta_d, phi_d = frenbrdf.merl_bin_angles()
    i = np.arange(90)
    np.testing.assert_allclose(theta_h, (i / 90) ** 2 * HALF_PI, rtol=1e-15)
    np.testing.assert_allclose(theta_d, i / 90 * HALF_PI, rtol=1e-15)
    np.testing.assert_allclose(phi_d, np.arange(180) / 180 * np.pi, rtol=1e-15)


def test_every_bin_maps_to_its_angles_and_back():
    bins = np.stack(np.meshgrid(np.arange(90), np.arange(90), np.arange(180), indexing="ij"), axis=-1)
    angles = frenbrdf.merl_bin_to_angles(bins)
    np.testing.assert_array_equal(frenbrdf.merl_angles_to_bin(angles), bins)


@settings(max_examples=200, deadline=None)
@given(
    theta_h=st.floats(0, HALF_PI), theta_d=st.floats(0, HALF_PI), phi_d=st.floats(-np.pi, np.pi - 1e-9)
)
def test_angles_to_bin_agrees_with_merls_reference_reader(theta_h, theta_d, phi_d):
    ours = frenbrdf.merl_angles_to_bin(np.array([theta_h, theta_d, phi_d]))
    reference = merl_reference_bins(theta_h, theta_d, phi_d)
    # Ours snaps indices within 1e-9 of an integer to it (so bin angles map back to
    # their bin), and folds φ_d = π − ε (bin 179) and 0 together periodically. Elsewhere
    # the two agree exactly.
    difference = ours - reference
    difference[2] = (difference[2] + 90) % 180 - 90
    assert np.all(np.abs(difference) <= 1)
    continuous = np.array([np.sqrt(theta_h / HALF_PI) * 90, theta_d / HALF_PI * 90, (phi_d % np.pi) / np.pi * 180])
    near_integer = np.abs(continuous - np.round(continuous)) < 1e-8
    assert np.all((difference == 0) | near_integer)


def test_lookup_at_bin_angles_returns_the_bin(merl_table):
    rng = np.random.default_rng(1)
    bins = np.stack([rng.integers(0, 90, 500), rng.integers(0, 90, 500), rng.integers(0, 180, 500)], axis=-1)
    angles = frenbrdf.merl_bin_to_angles(bins)
    expected = merl_table[:, bins[:, 0], bins[:, 1], bins[:, 2]].T
    for method in ("nearest", "trilinear"):
        got = frenbrdf.merl_lookup(merl_table, angles[:, 0], angles[:, 1], angles[:, 2], method=method)
        np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_trilinear_interpolates_halfway_between_bins():
    table = np.ones(SHAPE)
    table[:, 10, 20, 30] = 3.0
    theta_h, theta_d, phi_d = frenbrdf.merl_bin_to_angles(np.array([10.0, 20.5, 30.0]))
    rgb = frenbrdf.merl_lookup(table, theta_h, theta_d, phi_d)
    np.testing.assert_allclose(rgb, [2.0, 2.0, 2.0])
    assert frenbrdf.merl_lookup(table, theta_h, theta_d, phi_d, method="nearest").shape == (3,)


def test_phi_d_is_periodic_with_period_pi():
    table = np.zeros(SHAPE)
    table[:, 40, 40, 179] = 1.0
    table[:, 40, 40, 0] = 3.0
    theta_h, theta_d, _ = frenbrdf.merl_bin_to_angles(np.array([40.0, 40.0, 0.0]))
    halfway = np.pi * 179.5 / 180
    for phi in (halfway, halfway - np.pi, halfway + np.pi):
        np.testing.assert_allclose(frenbrdf.merl_lookup(table, theta_h, theta_d, phi), [2.0] * 3)


def test_missing_corners_are_skipped_and_all_missing_is_reported():
    table = np.ones(SHAPE)
    table[:, 10, 20, 30] = -1.0
    theta_h, theta_d, phi_d = frenbrdf.merl_bin_to_angles(np.array([10.0, 20.5, 30.0]))
    np.testing.assert_allclose(frenbrdf.merl_lookup(table, theta_h, theta_d, phi_d), [1.0] * 3)
    table[:] = -1.0
    assert np.all(frenbrdf.merl_lookup(table, theta_h, theta_d, phi_d) < 0)


def test_lookup_broadcasts_and_handles_millions_of_queries(merl_table):
    rng = np.random.default_rng(2)
    n = 2_000_000
    theta_h, theta_d, phi_d = rng.uniform(0, HALF_PI, n), rng.uniform(0, HALF_PI, n), rng.uniform(-np.pi, np.pi, n)
    rgb = frenbrdf.merl_lookup(merl_table, theta_h, theta_d, phi_d)
    assert rgb.shape == (n, 3) and np.isfinite(rgb).all()
    grid = frenbrdf.merl_lookup(merl_table, theta_h[:5, None], theta_d[None, :4], 0.3)
    assert grid.shape == (5, 4, 3)


def test_direction_lookup_equals_angle_lookup(merl_table):
    rng = np.random.default_rng(3)
    wi, wo = rng.normal(size=(1000, 3)), rng.normal(size=(1000, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    angles = frenbrdf.directions_to_rusinkiewicz(wi, wo)
    expected = frenbrdf.merl_lookup(merl_table, angles[:, 0], angles[:, 2], angles[:, 3])
    np.testing.assert_array_equal(frenbrdf.merl_lookup_directions(merl_table, wi, wo), expected)


def test_directions_below_the_horizon_are_missing():
    table = np.ones(SHAPE)
    wi = np.array([[0.0, 0.0, 1.0], [0.0, 0.6, -0.8]])
    wo = np.array([[0.6, 0.0, 0.8], [0.0, 0.0, 1.0]])
    rgb = frenbrdf.merl_lookup_directions(table, wi, wo)
    np.testing.assert_array_equal(rgb[0], [1.0] * 3)
    assert np.all(rgb[1] < 0)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda t: frenbrdf.merl_lookup(t, np.nan, 0.1, 0.1), "not finite"),
        (lambda t: frenbrdf.merl_lookup(t, 0.1, 0.1, 0.1, method="cubic"), "method must be"),
        (lambda t: frenbrdf.merl_lookup(t[:, :45], 0.1, 0.1, 0.1), r"shape \(3, 90, 90, 180\)"),
        (lambda t: frenbrdf.merl_lookup_directions(t, np.ones((2, 3)), np.ones((3, 3))), "same shape"),
        (lambda t: frenbrdf.merl_lookup_directions(t, np.zeros((1, 3)), np.ones((1, 3))), "wi row 0"),
        (lambda t: frenbrdf.merl_lookup_directions(t, np.ones((1, 2)), np.ones((1, 2))), r"wi must have shape"),
    ],
)
def test_bad_lookup_arguments_raise_value_errors(call, message):
    with pytest.raises(ValueError, match=message):
        call(np.ones(SHAPE))
