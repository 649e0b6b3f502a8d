"""Rusinkiewicz coordinates: round trips, reciprocity, ranges, poles and grazing angles."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import frenbrdf

from .conftest import unit_vectors

HALF_PI = np.pi / 2


def spherical(theta, phi):
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


# Directions on the upper hemisphere, including exactly the pole and the horizon.
polar = st.one_of(st.floats(0, HALF_PI), st.sampled_from([0.0, HALF_PI, 1e-300, HALF_PI - 1e-12]))
azimuth = st.floats(-np.pi, np.pi)
direction = st.tuples(polar, azimuth).map(lambda a: spherical(*a))
pairs = st.lists(st.tuples(direction, direction), min_size=1, max_size=50).map(
    lambda rows: (np.array([r[0] for r in rows]), np.array([r[1] for r in rows]))
)


def wrapped(angle):
    return (angle + np.pi) % (2 * np.pi) - np.pi


@settings(max_examples=200, deadline=None)
@given(pairs)
def test_directions_round_trip(pair):
    wi, wo = pair
    angles = frenbrdf.directions_to_rusinkiewicz(wi, wo)
    wi2, wo2 = frenbrdf.rusinkiewicz_to_directions(angles)
    if np.any(np.linalg.norm(wi + wo, axis=1) < 1e-6):
        return  # ω_i = −ω_o: H is undefined there, checked separately below
    np.testing.assert_allclose(wi2, wi, atol=1e-12)
    np.testing.assert_allclose(wo2, wo, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(1e-3, HALF_PI), st.floats(-np.pi + 1e-9, np.pi), st.floats(1e-3, HALF_PI - 1e-3), st.floats(-np.pi + 1e-9, np.pi)),
        min_size=1,
        max_size=50,
    )
)
def test_angles_round_trip(rows):
    """Polar angles to 1e-12; azimuths to 1e-12 plus their conditioning.

    An azimuth is ill-conditioned near its pole, and H = normalize(ω_i + ω_o) loses
    digits as ω_i → −ω_o (θ_d → π/2). An error in φ_h rotates the difference frame, so
    it reaches φ_d too: both tolerances grow as 1/(sin θ_h cos θ_d) + 1/(sin θ_d cos θ_d).
    """
    angles = np.array(rows)
    back = frenbrdf.directions_to_rusinkiewicz(*frenbrdf.rusinkiewicz_to_directions(angles))
    np.testing.assert_allclose(back[:, [0, 2]], angles[:, [0, 2]], atol=1e-12)
    theta_h, theta_d = angles[:, 0], angles[:, 2]
    condition = 1 / (np.sin(theta_h) * np.cos(theta_d)) + 1 / (np.sin(theta_d) * np.cos(theta_d))
    for column in (1, 3):
        error = np.abs(wrapped(back[:, column] - angles[:, column]))
        assert np.all(error <= 1e-12 + 1e-15 * condition), (error, condition)


@settings(max_examples=200, deadline=None)
@given(pairs)
def test_reciprocity(pair):
    wi, wo = pair
    forward = frenbrdf.directions_to_rusinkiewicz(wi, wo)
    backward = frenbrdf.directions_to_rusinkiewicz(wo, wi)
    np.testing.assert_allclose(backward[:, [0, 2]], forward[:, [0, 2]], atol=1e-12)
    # φ_h matters only off the pole, φ_d only off the pole of the difference frame.
    off_pole = (forward[:, 0] > 1e-6) & (forward[:, 2] > 1e-6)
    np.testing.assert_allclose(wrapped(backward[off_pole, 1] - forward[off_pole, 1]), 0, atol=1e-9)
    np.testing.assert_allclose(wrapped(backward[off_pole, 3] - forward[off_pole, 3] - np.pi), 0, atol=1e-9)


@settings(max_examples=200, deadline=None)
@given(pairs)
def test_value_ranges_on_the_upper_hemisphere(pair):
    angles = frenbrdf.directions_to_rusinkiewicz(*pair)
    assert np.isfinite(angles).all()
    assert np.all((0 <= angles[:, [0, 2]]) & (angles[:, [0, 2]] <= HALF_PI + 1e-15))
    assert np.all((-np.pi <= angles[:, [1, 3]]) & (angles[:, [1, 3]] <= np.pi))


finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


@settings(max_examples=200, deadline=None)
@given(arrays(np.float64, (20, 3), elements=finite), arrays(np.float64, (20, 3), elements=finite))
def test_never_nan_for_any_nonzero_directions(wi, wo):
    wi[np.linalg.norm(wi, axis=1) == 0] = [0.0, 0.0, 1.0]
    wo[np.linalg.norm(wo, axis=1) == 0] = [0.0, 0.0, 1.0]
    assert np.isfinite(frenbrdf.directions_to_rusinkiewicz(wi, wo)).all()
    h, d = frenbrdf.half_diff_vectors(wi, wo)
    np.testing.assert_allclose(np.linalg.norm(h, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)


def test_poles_and_grazing_angles():
    up = np.array([0.0, 0.0, 1.0])
    np.testing.assert_array_equal(frenbrdf.directions_to_rusinkiewicz(up, up), [0, 0, 0, 0])
    grazing = spherical(HALF_PI, 0.3)
    np.testing.assert_allclose(frenbrdf.directions_to_rusinkiewicz(grazing, grazing)[[0, 2]], [HALF_PI, 0], atol=1e-15)
    # Opposite grazing directions: H is undefined; we take the limit, the pole.
    np.testing.assert_allclose(frenbrdf.directions_to_rusinkiewicz(grazing, -grazing)[[0, 2]], [0, HALF_PI], atol=1e-15)
    # Mirror pair: θ_h = 0 and θ_d = the angle of incidence.
    wi = spherical(0.7, 2.0)
    mirror = np.array([-wi[0], -wi[1], wi[2]])
    np.testing.assert_allclose(frenbrdf.directions_to_rusinkiewicz(wi, mirror)[[0, 2]], [0, 0.7], atol=1e-15)


def test_half_diff_vectors_agree_with_their_definitions():
    rng = np.random.default_rng(0)
    wi, wo = unit_vectors(rng, 1000), unit_vectors(rng, 1000)
    h, d = frenbrdf.half_diff_vectors(wi, wo)
    expected_h = (wi + wo) / np.linalg.norm(wi + wo, axis=1, keepdims=True)
    np.testing.assert_allclose(h, expected_h, atol=1e-12)
    np.testing.assert_allclose(np.sum(d * [0, 0, 1], axis=1), np.sum(wi * h, axis=1), atol=1e-12)  # cos θ_d
    h2, d2 = frenbrdf.rusinkiewicz_to_half_diff(frenbrdf.directions_to_rusinkiewicz(wi, wo))
    np.testing.assert_allclose(h2, h, atol=1e-12)
    np.testing.assert_allclose(d2, d, atol=1e-12)


def test_leading_dimensions_are_kept():
    rng = np.random.default_rng(1)
    wi, wo = unit_vectors(rng, 24).reshape(2, 3, 4, 3), unit_vectors(rng, 24).reshape(2, 3, 4, 3)
    angles = frenbrdf.directions_to_rusinkiewicz(wi, wo)
    assert angles.shape == (2, 3, 4, 4)
    assert frenbrdf.rusinkiewicz_to_directions(angles)[0].shape == (2, 3, 4, 3)
    assert frenbrdf.directions_to_rusinkiewicz(wi[:0], wo[:0]).shape == (0, 3, 4, 4)


def test_many_rows_in_parallel_match_row_by_row():
    rng = np.random.default_rng(2)
    wi, wo = unit_vectors(rng, 1_000_000), unit_vectors(rng, 1_000_000)
    batched = frenbrdf.directions_to_rusinkiewicz(wi, wo)
    for row in rng.integers(0, 1_000_000, 20):
        np.testing.assert_array_equal(frenbrdf.directions_to_rusinkiewicz(wi[row], wo[row]), batched[row])


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: frenbrdf.directions_to_rusinkiewicz([[np.nan, 0, 1]], [[0, 0, 1]]), "wi row 0"),
        (lambda: frenbrdf.directions_to_rusinkiewicz([[0, 0, 1], [0, 0, 0]], [[0, 0, 1]] * 2), "wi row 1"),
        (lambda: frenbrdf.half_diff_vectors([[0, 0, 1]], [[0, 0, np.inf]]), "wo row 0"),
        (lambda: frenbrdf.directions_to_rusinkiewicz([[0, 0, 1]], [[0, 0, 1]] * 2), "same shape"),
        (lambda: frenbrdf.directions_to_rusinkiewicz([[0, 1]], [[0, 1]]), r"wi must have shape \(\.\.\., 3\)"),
        (lambda: frenbrdf.rusinkiewicz_to_directions([[0.1, 0.2, np.nan, 0.3]]), "angles row 0"),
        (lambda: frenbrdf.rusinkiewicz_to_half_diff([[0.1, 0.2, 0.3]]), r"shape \(\.\.\., 4\)"),
        (lambda: frenbrdf.rusinkiewicz_to_directions(np.array([["a", "b", "c", "d"]])), "real numbers"),
    ],
)
def test_bad_input_raises_value_errors(call, message):
    with pytest.raises(ValueError, match=message):
        call()
