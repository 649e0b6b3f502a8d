"""kNN Gaussian interpolation on the sphere: equal to brute force, stable where it fails."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import frenbrdf

from .conftest import unit_vectors


def brute_force(src, values, dst, k, sigma):
    """The definition (paper Eq. 5–7) in numpy, weights relative to the nearest."""
    d2 = ((dst[:, None, :] - src[None, :, :]) ** 2).sum(-1)
    nearest = np.argsort(d2, axis=1, kind="stable")[:, :k]
    d2k = np.take_along_axis(d2, nearest, axis=1)
    w = np.exp(-(d2k - d2k[:, :1]) / (2 * sigma**2))
    w /= w.sum(axis=1, keepdims=True)
    return np.einsum("mk,mkc->mc", w, values[nearest]), nearest, w


@settings(max_examples=100, deadline=None)
@given(
    n=st.integers(1, 300),
    m=st.integers(0, 50),
    k=st.integers(1, 12),
    sigma=st.floats(1e-3, 2.0),
    channels=st.integers(1, 4),
    seed=st.integers(0, 2**32 - 1),
)
def test_equals_brute_force(n, m, k, sigma, channels, seed):
    rng = np.random.default_rng(seed)
    k = min(k, n)
    src, dst = unit_vectors(rng, n), unit_vectors(rng, m)
    values = rng.normal(size=(n, channels))
    expected, nearest, weights = brute_force(src, values, dst, k, sigma)

    op = frenbrdf.KnnInterpolator(src, dst, k, sigma)
    np.testing.assert_allclose(op.apply(values), expected, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(op.indices, nearest)
    np.testing.assert_allclose(op.weights, weights, rtol=1e-10)
    np.testing.assert_allclose(frenbrdf.knn_interpolate(src, values, dst, k, sigma), expected, rtol=1e-10, atol=1e-12)


def test_one_operator_serves_many_value_sets():
    rng = np.random.default_rng(0)
    src, dst = unit_vectors(rng, 5000), unit_vectors(rng, 800)
    op = frenbrdf.KnnInterpolator(src, dst, k=8, sigma=0.05)
    assert (op.n_src, op.n_dst, op.k) == (5000, 800, 8)
    for _ in range(3):
        values = rng.uniform(size=(5000, 3))
        np.testing.assert_allclose(op.apply(values), brute_force(src, values, dst, 8, 0.05)[0], rtol=1e-10)
    scalar = rng.uniform(size=5000)
    assert op.apply(scalar).shape == (800,)
    np.testing.assert_allclose(op.apply(scalar), op.apply(scalar[:, None])[:, 0])
    np.testing.assert_allclose(op.weights.sum(axis=1), 1.0, rtol=1e-14)


@pytest.mark.parametrize("sigma", [1e-6, 1e-30, 1e-200, 5e-324])
def test_tiny_sigma_returns_the_nearest_value_never_nan(sigma):
    rng = np.random.default_rng(1)
    src, dst = unit_vectors(rng, 2000), unit_vectors(rng, 300)
    values = rng.normal(size=(2000, 2))
    out = frenbrdf.knn_interpolate(src, values, dst, k=8, sigma=sigma)
    nearest = brute_force(src, values, dst, 1, 1.0)[1][:, 0]
    assert np.isfinite(out).all()
    np.testing.assert_array_equal(out, values[nearest])


def test_duplicate_points_at_the_pole():
    """On the (θ_d, φ_d) sphere every φ_d at θ_d = 0 is the same point: the pole."""
    rng = np.random.default_rng(2)
    pole = np.tile([0.0, 0.0, 1.0], (180, 1))
    others = unit_vectors(rng, 500)
    src = np.concatenate([pole, others])
    values = np.concatenate([np.full(180, 2.0), rng.normal(size=500)])
    op = frenbrdf.KnnInterpolator(src, np.array([[0.0, 0.0, 1.0]]), k=8, sigma=0.01)
    np.testing.assert_allclose(op.weights, np.full((1, 8), 1 / 8))
    assert set(op.indices[0]) <= set(range(180))
    np.testing.assert_allclose(op.apply(values), [2.0])


def test_all_sources_identical():
    src = np.tile([1.0, 0.0, 0.0], (1000, 1))
    out = frenbrdf.knn_interpolate(src, np.arange(1000.0), np.array([[0.0, 1.0, 0.0]]), k=1000, sigma=0.1)
    np.testing.assert_allclose(out, [499.5])


@pytest.mark.parametrize(
    "arguments, message",
    [
        (dict(k=0), r"k = 0 must be between 1 and the number of sources \(10\)"),
        (dict(k=11), r"k = 11 must be between 1 and the number of sources \(10\)"),
        (dict(k=2.5), "k must be an integer"),
        (dict(sigma=0.0), "sigma = 0 must be a finite positive number"),
        (dict(sigma=-1.0), "sigma = -1 must be"),
        (dict(sigma=float("nan")), "sigma = NaN must be"),
        (dict(sigma=float("inf")), "sigma = inf must be"),
        (dict(src=np.full((10, 3), 0.5)), r"src row 0 = \[0.5, 0.5, 0.5\] is not a unit vector"),
        (dict(dst=np.array([[0.0, 0.0, 1.0], [np.nan, 0.0, 1.0]])), "dst row 1 .* is not a unit vector"),
        (dict(src=np.zeros((0, 3))), "src must be a non-empty"),
        (dict(src=np.ones((10, 2))), r"src must have shape \(\.\.\., 3\)"),
        (dict(dst=np.ones((2, 2, 3)) / np.sqrt(3)), r"dst must be an \(M, 3\) array"),
    ],
)
def test_bad_arguments_raise_value_errors(arguments, message):
    rng = np.random.default_rng(3)
    call = dict(src=unit_vectors(rng, 10), dst=unit_vectors(rng, 4), k=3, sigma=0.1) | arguments
    with pytest.raises(ValueError, match=message):
        frenbrdf.KnnInterpolator(**call)


@pytest.mark.parametrize(
    "values, message",
    [
        (np.ones(9), r"values must have shape \(10,\) or \(10, C\)"),
        (np.ones((10, 2, 2)), "values must have shape"),
        (np.array([1.0] * 9 + [np.nan]), "values row 9 is not finite"),
    ],
)
def test_bad_values_raise_value_errors(values, message):
    rng = np.random.default_rng(4)
    op = frenbrdf.KnnInterpolator(unit_vectors(rng, 10), unit_vectors(rng, 4), k=3, sigma=0.1)
    with pytest.raises(ValueError, match=message):
        op.apply(values)


def test_merl_sized_problem_matches_brute_force_on_a_sample():
    """As many sources as a MERL table has samples; checked against brute force on 20 targets."""
    rng = np.random.default_rng(5)
    src, dst = unit_vectors(rng, 1_458_000), unit_vectors(rng, 20_000)
    values = rng.uniform(size=(1_458_000, 3))
    out = frenbrdf.knn_interpolate(src, values, dst, k=8, sigma=0.002)
    rows = rng.choice(20_000, 20, replace=False)
    np.testing.assert_allclose(out[rows], brute_force(src, values, dst[rows], 8, 0.002)[0], rtol=1e-10)


def merl_slice_directions() -> np.ndarray:
    """The bins of one MERL θ_h slice as directions (θ_d, φ_d), with their reciprocal
    copies φ_d + π, as the frequency-loss truth builds them: 90 × 360 unit vectors.

    360 of them are exactly the pole, and the first rings around it are 1° apart in θ_d
    but only 3·10⁻⁴ apart along the ring: a heavily clustered source set.
    """
    _, theta_d, phi_d = frenbrdf.merl_bin_angles()
    theta, phi = np.meshgrid(theta_d, np.concatenate([phi_d, phi_d + np.pi]), indexing="ij")
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1).reshape(-1, 3)


def test_heavily_clustered_sources_match_brute_force():
    """MERL's slice grid plus one exact and three 10⁻⁹-jittered copies of its 2,160 bins
    within 5.5° of the pole: 720 exact copies of the pole, 1,080 more within 10⁻⁹ of it,
    and 8,640 extra points in all around it, in rings whose points share their z exactly.

    Values are a smooth function of position, so choosing one of several equally near
    duplicates changes the result by at most the jitter; queries avoid exact symmetric ties
    (other than the pole itself, whose duplicates carry the same value).
    """
    rng = np.random.default_rng(6)
    grid = merl_slice_directions()
    near_pole = grid[grid[:, 2] > np.cos(np.radians(5.5))]
    jittered = np.repeat(near_pole, 3, axis=0) + rng.normal(scale=1e-9, size=(3 * len(near_pole), 3))
    jittered /= np.linalg.norm(jittered, axis=1, keepdims=True)
    src = np.concatenate([grid, near_pole, jittered])
    assert np.sum(np.all(src == [0.0, 0.0, 1.0], axis=1)) == 2 * 360
    values = np.stack([src[:, 0] + 2 * src[:, 1], np.exp(src[:, 2]) * src[:, 0], np.cos(3 * src[:, 1])], axis=-1)

    theta = np.radians(rng.uniform(0, 3, 150))  # within the clusters near the pole
    phi = rng.uniform(0, 2 * np.pi, 150)
    near = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    on_bins = grid[rng.choice(len(grid), 50, replace=False)] + rng.normal(scale=1e-6, size=(50, 3))
    dst = np.concatenate([[[0.0, 0.0, 1.0]], near, on_bins, unit_vectors(rng, 150)])
    dst /= np.linalg.norm(dst, axis=1, keepdims=True)

    k, sigma = 16, 0.01
    op = frenbrdf.KnnInterpolator(src, dst, k, sigma)
    expected, nearest, _ = brute_force(src, values, dst, k, sigma)
    # The same neighbour distances (ties among duplicates may name other, equally near, indices).
    def squared_distances(indices):
        return ((dst[:, None, :] - src[indices]) ** 2).sum(-1)

    np.testing.assert_allclose(squared_distances(op.indices), squared_distances(nearest), rtol=1e-12, atol=1e-30)
    assert np.isfinite(op.weights).all()
    np.testing.assert_allclose(op.weights.sum(axis=1), 1.0, rtol=1e-14)
    np.testing.assert_allclose(op.apply(values), expected, rtol=1e-8, atol=1e-8)
    # At the pole every neighbour is an exact or near duplicate of it, equally weighted.
    assert np.all(src[op.indices[0], 2] > 1 - 1e-15)
    np.testing.assert_allclose(op.weights[0], np.full(k, 1 / k), rtol=1e-12)
