"""Spherical harmonic transform: exactness, orthonormality, adjoint, autograd, peers."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from frenbrdf.numerics.sht import SHT
from frenbrdf.numerics.sht_torch import SHTAnalysis, SHTAnalysisFunction

GRIDS = [("gauss", 0), ("equiangular", 1)]  # (grid, rings beyond lmax + 1 that it needs)


def random_coefficients(sht: SHT, batch: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).normal(size=(batch, sht.n_coefficients))


def relative_error(actual: np.ndarray, expected: np.ndarray) -> float:
    return float(np.abs(actual - expected).max() / np.abs(expected).max())


@pytest.mark.parametrize("grid, extra", GRIDS)
def test_round_trip_lmax_89_float64(grid, extra):
    sht = SHT(90 + extra, 180, 89, grid)
    coefficients = random_coefficients(sht, 5)
    for _ in range(3):  # repeated: plans and scratch buffers are reused between calls
        assert relative_error(sht.analysis(sht.synthesis(coefficients)), coefficients) <= 1e-12


@pytest.mark.parametrize("grid, extra", GRIDS)
def test_round_trip_lmax_1023_float64(grid, extra):
    sht = SHT(1024 + extra, 2048, 1023, grid)
    coefficients = random_coefficients(sht, 1)
    assert relative_error(sht.analysis(sht.synthesis(coefficients)), coefficients) <= 1e-11


@pytest.mark.parametrize("grid, extra", GRIDS)
def test_round_trip_float32(grid, extra):
    sht = SHT(90 + extra, 180, 89, grid, dtype="float32")
    coefficients = random_coefficients(sht, 4).astype(np.float32)
    maps = sht.synthesis(coefficients)
    assert maps.dtype == np.float32
    assert relative_error(sht.analysis(maps), coefficients) <= 1e-5


@settings(max_examples=60, deadline=None)
@given(lmax=st.integers(0, 24), grid=st.sampled_from(["gauss", "equiangular"]), data=st.data())
def test_basis_is_orthonormal_under_the_grid_quadrature(lmax, grid, data):
    nlat = lmax + (1 if grid == "gauss" else 2)
    sht = SHT(nlat, 2 * lmax + 1 + data.draw(st.integers(0, 3)), lmax, grid)
    n = sht.n_coefficients
    i, j = data.draw(st.integers(0, n - 1)), data.draw(st.integers(0, n - 1))
    y_i, y_j = sht.synthesis(np.eye(n)[[i, j]])
    if grid == "gauss":
        # The grid's own quadrature, point weights w_j · 2π/nlon.
        weights = sht.weights[:, None] * 2 * np.pi / sht.nlon
        assert abs(np.sum(weights * y_i * y_j) - (i == j)) < 1e-12
    # Analysis is the quadrature the transform uses on either grid.
    np.testing.assert_allclose(sht.analysis(y_j), np.eye(n)[j], atol=1e-12)


def test_analytic_low_degree_maps():
    sht = SHT(8, 17, 6)
    theta = sht.theta[:, None]
    phi = 2 * np.pi * np.arange(17)[None, :] / 17
    lm = [tuple(pair) for pair in sht.degrees_orders()]
    cases = {
        (0, 0): np.ones_like(theta * phi),                       # Y00 = 1/√(4π)
        (1, 0): np.cos(theta) + 0 * phi,                         # Y10 = √(3/4π) cos θ
        (1, 1): np.sin(theta) * np.cos(phi),                     # cosine part of m = 1
        (1, -1): np.sin(theta) * np.sin(phi),                    # sine part of m = 1
    }
    expected = {(0, 0): np.sqrt(4 * np.pi), (1, 0): np.sqrt(4 * np.pi / 3),
                (1, 1): np.sqrt(4 * np.pi / 3), (1, -1): np.sqrt(4 * np.pi / 3)}
    for key, values in cases.items():
        coefficients = sht.analysis(values)
        target = np.zeros(sht.n_coefficients)
        target[lm.index(key)] = expected[key]
        np.testing.assert_allclose(coefficients, target, atol=1e-13)
    # 3 cos² θ − 1 = 4 √(π/5) Y20 (plus nothing else)
    coefficients = sht.analysis(3 * np.cos(theta) ** 2 - 1 + 0 * phi)
    assert abs(coefficients[lm.index((2, 0))] - 4 * np.sqrt(np.pi / 5)) < 1e-13


def test_layout_of_degrees_and_orders():
    lm = SHT(4, 7, 3).degrees_orders()
    assert lm.shape == (16, 2)
    expected = [(l, 0) for l in range(4)] + [(l, 1) for l in (1, 2, 3)] + [(l, -1) for l in (1, 2, 3)] \
        + [(2, 2), (3, 2), (2, -2), (3, -2), (3, 3), (3, -3)]
    assert [tuple(p) for p in lm] == expected


@pytest.mark.parametrize("grid, extra", GRIDS)
def test_adjoint_satisfies_the_dot_product_identity(grid, extra):
    sht = SHT(30 + extra, 61, 29, grid)
    rng = np.random.default_rng(1)
    maps, coefficients = rng.normal(size=(3, sht.nlat, sht.nlon)), rng.normal(size=(3, sht.n_coefficients))
    lhs = np.sum(sht.analysis(maps) * coefficients)
    rhs = np.sum(maps * sht.analysis_adjoint(coefficients))
    assert abs(lhs - rhs) <= 1e-12 * abs(lhs)


@pytest.mark.parametrize("grid, extra", GRIDS)
def test_torch_gradcheck(grid, extra):
    analysis = SHTAnalysis(6 + extra, 11, 5, grid)
    maps = torch.randn(2, analysis.nlat, 11, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(analysis, (maps,))


def test_torch_module_follows_the_input_dtype():
    analysis = SHTAnalysis(16, 32, 15)
    maps = torch.randn(3, 2, 16, 32, dtype=torch.float32, requires_grad=True)
    coefficients = analysis(maps)
    assert coefficients.shape == (3, 2, 256) and coefficients.dtype == torch.float32
    coefficients.square().sum().backward()
    assert maps.grad.shape == maps.shape and torch.isfinite(maps.grad).all()
    sht = analysis.plan(torch.float64)
    expected = sht.analysis(maps.detach().double().numpy())
    np.testing.assert_allclose(coefficients.detach().numpy(), expected, rtol=1e-4, atol=1e-4)
    assert SHTAnalysisFunction.apply(maps.double(), sht).shape == (3, 2, 256)


def test_complex_layout_round_trip():
    sht = SHT(12, 23, 11)
    coefficients = random_coefficients(sht, 3)
    alm = sht.to_complex(coefficients)
    assert alm.shape == (3, 12, 12)
    assert np.all(np.triu(np.ones((12, 12)), 1)[None] * alm == 0)  # m > l is empty
    np.testing.assert_allclose(sht.from_complex(alm), coefficients, atol=1e-15)


ducc0 = pytest.importorskip("ducc0", reason="ducc0 is an optional peer: pip install ducc0")


def ducc0_packed(alm: np.ndarray, lmax: int) -> np.ndarray:
    """Our [l, m] complex layout → ducc0's packed m-major layout."""
    return np.concatenate([alm[m:, m] for m in range(lmax + 1)])


@pytest.mark.parametrize("grid, geometry, extra", [("gauss", "GL", 0), ("equiangular", "CC", 1)])
def test_agrees_with_ducc0(grid, geometry, extra):
    lmax = 40
    sht = SHT(lmax + 1 + extra, 2 * lmax + 2, lmax, grid)
    coefficients = random_coefficients(sht, 1)[0]
    packed = ducc0_packed(sht.to_complex(coefficients), lmax)
    theirs = ducc0.sht.experimental.synthesis_2d(
        alm=packed[None], spin=0, lmax=lmax, geometry=geometry, ntheta=sht.nlat, nphi=sht.nlon
    )[0]
    ours = sht.synthesis(coefficients)
    assert relative_error(ours, theirs) <= 1e-10
    back = ducc0.sht.experimental.analysis_2d(
        map=ours[None], spin=0, lmax=lmax, geometry=geometry
    )[0]
    assert relative_error(ducc0_packed(sht.to_complex(sht.analysis(ours)), lmax), back) <= 1e-10


# --- bad input --------------------------------------------------------------------


@pytest.mark.parametrize(
    "arguments, message",
    [
        (dict(nlat=11, nlon=20, lmax=10), r"nlon = 20 is too small for lmax = 10: need nlon ≥ 2·lmax \+ 1 = 21"),
        (dict(nlat=10, nlon=21, lmax=10), r"nlat = 10 rings are too few .* Gauss–Legendre grid: need nlat ≥ 11"),
        (dict(nlat=11, nlon=21, lmax=10, grid="equiangular"), r"equiangular grid: need nlat ≥ 12"),
        (dict(nlat=10, nlon=21, lmax=-1), "lmax = -1 must be ≥ 0"),
        (dict(nlat=10, nlon=21, lmax=2.5), "lmax must be an integer"),
        (dict(nlat=10, nlon=21, lmax=5, grid="healpix"), "grid must be one of"),
        (dict(nlat=10, nlon=21, lmax=5, dtype="float16"), "dtype must be one of"),
    ],
)
def test_bad_plans_raise_value_errors(arguments, message):
    with pytest.raises(ValueError, match=message):
        SHT(**arguments)


def test_bad_arrays_raise_value_errors():
    sht = SHT(8, 16, 7)
    with pytest.raises(ValueError, match=r"maps must have shape \(\.\.\., 8, 16\), got \(8, 15\)"):
        sht.analysis(np.zeros((8, 15)))
    with pytest.raises(ValueError, match=r"coefficients must have shape \(\.\.\., 64\), got \(2, 63\)"):
        sht.synthesis(np.zeros((2, 63)))
    with pytest.raises(ValueError, match="real numbers"):
        sht.analysis(np.zeros((8, 16), dtype=complex))


def test_nan_stays_in_its_own_map():
    sht = SHT(8, 16, 7)
    maps = np.ones((2, 8, 16))
    maps[0, 3, 4] = np.nan
    coefficients = sht.analysis(maps)
    assert np.isnan(coefficients[0]).any()
    assert np.isfinite(coefficients[1]).all()


@pytest.mark.slow
def test_round_trip_lmax_4095_without_overflow():
    """The scaled recurrence at the top of its range (measured: 5.8e-12, about 2.5 minutes here)."""
    sht = SHT(4096, 8192, 4095, "gauss")
    coefficients = np.random.default_rng(0).normal(size=sht.n_coefficients)
    maps = sht.synthesis(coefficients)
    assert np.all(np.isfinite(maps))
    back = sht.analysis(maps)
    assert np.max(np.abs(back - coefficients)) <= 1e-10 * np.max(np.abs(coefficients))
