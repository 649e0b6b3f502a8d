"""Decoded BRDFs are reciprocal and isotropic: f(ω_i, ω_o) = f(ω_o, ω_i), and turning both
directions about the normal changes nothing (docs/method.md §1: MERL tables cover φ_d ∈ [0, π)
only, so the NBRDF input D is folded onto D_y ≥ 0)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

import frenbrdf
from frenbrdf.data.nbrdf_import import keras_nbrdf
from frenbrdf.io.keras import read_keras_nbrdf
from frenbrdf.models import ModelConfig
from frenbrdf.models.autoencoder import AutoEncoder, Model
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.models.nbrdf import fold_difference, nbrdf_coordinates

from .conftest import PUBLISHED, needs_published, random_layers


def upper_hemisphere(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.02
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def rotate_about_normal(v: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]], axis=-1)


def decoded_nbrdf(seed: int):
    """A decoded material of an untrained model: an arbitrary network, as asymmetric as any."""
    torch.manual_seed(seed)
    config = ModelConfig()
    model = Model(AutoEncoder(config), LogRelativeMapping(np.full(3, 0.05)), config)
    return model.decode(np.random.default_rng(seed).normal(size=config.encoder.latent))[0]


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**16), angle=st.floats(0, 2 * np.pi))
def test_decoded_brdfs_are_reciprocal_and_isotropic(seed, angle):
    nbrdf = decoded_nbrdf(seed % 7)
    rng = np.random.default_rng(seed)
    wi, wo = upper_hemisphere(rng, 400), upper_hemisphere(rng, 400)
    f = nbrdf(wi, wo)
    np.testing.assert_allclose(nbrdf(wo, wi), f, rtol=2e-5, atol=1e-7)
    np.testing.assert_allclose(nbrdf(rotate_about_normal(wi, angle), rotate_about_normal(wo, angle)), f,
                               rtol=2e-5, atol=1e-7)


def test_an_unfolded_network_is_not_reciprocal():
    """What the fold repairs: the same network fed D unfolded gives another value for the swapped pair."""
    nbrdf = decoded_nbrdf(0)
    rng = np.random.default_rng(1)
    wi, wo = upper_hemisphere(rng, 400), upper_hemisphere(rng, 400)
    h, d = frenbrdf.half_diff_vectors(wi, wo)
    h_iso = nbrdf_coordinates(wi, wo)[:, :3]
    swapped_d = frenbrdf.half_diff_vectors(wo, wi)[1]
    one = nbrdf.mapped(np.concatenate([h_iso, d], axis=-1))
    other = nbrdf.mapped(np.concatenate([h_iso, swapped_d], axis=-1))
    assert np.median(np.abs(one - other)) > 1e-3


def test_the_fold_keeps_the_half_space_and_maps_the_other_by_reciprocity():
    d = np.array([[0.3, 0.4, 0.866], [0.3, -0.4, 0.866], [-0.5, 0.0, 0.866], [0.5, 0.0, 0.866]])
    np.testing.assert_array_equal(fold_difference(d), [[0.3, 0.4, 0.866], [-0.3, 0.4, 0.866], [0.5, 0.0, 0.866],
                                                       [0.5, 0.0, 0.866]])


def test_imported_networks_are_reciprocal():
    nbrdf = keras_nbrdf(random_layers([6, 8, 8, 3], seed=3))
    rng = np.random.default_rng(2)
    wi, wo = upper_hemisphere(rng, 500), upper_hemisphere(rng, 500)
    np.testing.assert_allclose(nbrdf(wo, wi), nbrdf(wi, wo), rtol=2e-5, atol=1e-7)


@needs_published
@pytest.mark.parametrize("path", PUBLISHED[:4], ids=lambda p: p.stem)
def test_published_networks_lose_nothing_by_the_fold(path):
    """The published fits learned φ_d over the whole circle (from a table mirrored by
    reciprocity): their value at a folded D is their value at D, to their fitting accuracy."""
    layers = read_keras_nbrdf(path)
    nbrdf = keras_nbrdf(layers)
    rng = np.random.default_rng(0)
    wi, wo = upper_hemisphere(rng, 4000), upper_hemisphere(rng, 4000)
    coords = nbrdf_coordinates(wi, wo)
    h, d = frenbrdf.half_diff_vectors(wi, wo)
    unfolded = np.concatenate([coords[:, :3], d], axis=-1)
    above = (wi[:, 2] > 0.1) & (wo[:, 2] > 0.1)  # away from grazing, where the fits extrapolate
    folded_values, unfolded_values = nbrdf.mapped(coords)[above], nbrdf.mapped(unfolded)[above]
    # The networks' output is ln(1 + f) per channel (exp(x) − 1): differences are in ln(1 + f).
    assert np.median(np.abs(folded_values - unfolded_values)) < 0.02
