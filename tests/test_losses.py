"""Losses: L_rec and the frequency-rectified loss."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from frenbrdf.data.folders import list_materials, split_materials
from frenbrdf.io.merl import merl_above_horizon
from frenbrdf.models import NBRDFConfig, nbrdf_forward
from frenbrdf.models.losses import (
    FrequencyLoss,
    FrequencyLossConfig,
    FrequencyTruth,
    reconstruction_loss,
    spectral_distance,
    weight_penalty,
)
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.models.nbrdf import bin_geometry
from frenbrdf.training import prepare

from .conftest import tiny

SMALL = FrequencyLossConfig(lmax=15, slices=(0, 20, 40))
NBRDF = NBRDFConfig((8, 8))


def smooth_params(seed: int, dtype=torch.float64) -> list[torch.Tensor]:
    generator = torch.Generator().manual_seed(seed)
    return [torch.randn(1, *s, generator=generator, dtype=dtype) * 0.4 for s in NBRDF.shapes()]


def table_of(params) -> np.ndarray:
    """The NBRDF at every MERL bin: ``(N_BINS, 3)`` mapped values."""
    coords = bin_geometry().half_diff.to(params[0].dtype)[None]
    return nbrdf_forward(params, coords)[0].numpy()


def test_reconstruction_loss_weights_by_cosine():
    predicted, true = torch.ones(1, 2, 3), torch.zeros(1, 2, 3)
    cos = torch.tensor([[1.0, 0.0]])
    assert float(reconstruction_loss(predicted, true, cos, "l1")) == pytest.approx(0.5)
    assert float(reconstruction_loss(2 * predicted, true, cos, "mse")) == pytest.approx(2.0)


def test_config_errors_name_the_field():
    with pytest.raises(ValueError, match="slices"):
        FrequencyLossConfig(slices=(0, 90))
    with pytest.raises(ValueError, match="sigma"):
        FrequencyLossConfig(sigma=0)
    with pytest.raises(ValueError, match="extension"):
        FrequencyLossConfig(extension="odd")


@pytest.mark.parametrize("extension", ["mirror", "zero"])
def test_truth_and_prediction_agree_for_the_same_brdf(extension):
    config = FrequencyLossConfig(lmax=15, slices=(0, 20, 40), extension=extension)
    valid = merl_above_horizon().reshape(-1)
    truth = FrequencyTruth(config)
    loss = FrequencyLoss(config).to(torch.float64)
    params, other = smooth_params(0), smooth_params(1)
    true = torch.from_numpy(truth.coefficients(table_of(params), valid))[None].to(torch.float64)
    same = float(loss(params, true))
    different = float(loss(other, true))
    # The truth passes through kNN interpolation of the bins; the prediction does not.
    assert same < 0.005 * different  # measured: about 1e-3


def test_frequency_loss_is_zero_for_identical_materials_and_grows_with_a_perturbation():
    valid = merl_above_horizon().reshape(-1)
    truth = FrequencyTruth(SMALL)
    table = table_of(smooth_params(0))
    reference = truth.coefficients(table, valid)
    rng = np.random.default_rng(0)
    noise = rng.normal(size=table.shape)
    losses = [np.mean((truth.coefficients(table + scale * noise, valid) - reference) ** 2)
              for scale in (0.0, 0.01, 0.1)]
    assert losses[0] == 0.0 and 0 < losses[1] < losses[2]


def test_frequency_loss_gradient_matches_finite_differences():
    loss = FrequencyLoss(FrequencyLossConfig(lmax=5, slices=(0, 30))).to(torch.float64)
    params = [p.requires_grad_() for p in smooth_params(2)]
    true = torch.randn(1, 2, 3, 36, dtype=torch.float64)
    assert torch.autograd.gradcheck(lambda *p: loss(list(p), true), params, eps=1e-6, atol=1e-6)


def test_truth_is_cached_on_disk(tmp_path):
    valid = merl_above_horizon().reshape(-1)
    table = table_of(smooth_params(0))
    first = FrequencyTruth(SMALL, tmp_path).coefficients(table, valid, cache_key="abc")
    files = list(tmp_path.glob("abc.npy"))
    assert len(files) == 1
    # A fresh instance reads the file instead of recomputing (a different table proves it).
    again = FrequencyTruth(SMALL, tmp_path).coefficients(table * 0, valid, cache_key="abc")
    np.testing.assert_array_equal(again, first)
    files[0].write_bytes(b"damaged")
    recomputed = FrequencyTruth(SMALL, tmp_path).coefficients(table, valid, cache_key="abc")
    np.testing.assert_allclose(recomputed, first)


def test_the_truth_cache_key_changes_with_everything_the_truth_depends_on():
    truth = FrequencyTruth(SMALL)
    mapping = LogRelativeMapping(np.full(3, 0.1), epsilon=0.002)
    key = truth.cache_key("material", mapping)
    assert key == FrequencyTruth(FrequencyLossConfig(lmax=15, slices=(0, 20, 40))).cache_key("material", mapping)
    others = [
        truth.cache_key("another material", mapping),
        truth.cache_key("material", LogRelativeMapping(np.full(3, 0.1), epsilon=0.01)),
        truth.cache_key("material", LogRelativeMapping(np.full(3, 0.2), epsilon=0.002)),
        truth.cache_key("material", LogRelativeMapping(np.full(3, 0.1), epsilon=0.002, offset=1.0)),
    ]
    for change in ({"lmax": 11}, {"slices": (0, 20)}, {"k": 3}, {"sigma": 0.1}, {"extension": "zero"},
                   {"grid": "equiangular"}):
        config = dataclasses.replace(SMALL, **change)
        others.append(FrequencyTruth(config).cache_key("material", mapping))
    assert key not in others and len(set(others)) == len(others)


def test_training_truth_follows_the_mapping_not_a_stale_cache(toy_materials, tmp_path):
    """Two runs on the same files that differ only in ε must not share the cached truth."""
    files = {path.stem: path for path in list_materials(toy_materials)}
    truths = []
    for epsilon in (0.002, 0.05):
        cfg = tiny("frenbrdf", toy_materials, tmp_path / f"run-{epsilon}")
        cfg.model.mapping.epsilon = epsilon
        cfg.cache_dir = str(tmp_path / "shared-cache")
        split = split_materials(files, cfg.seed, cfg.split)
        truths.append(prepare(cfg, split, files).truth)
    fresh = tiny("frenbrdf", toy_materials, tmp_path / "fresh")
    fresh.model.mapping.epsilon, fresh.cache_dir = 0.05, str(tmp_path / "fresh-cache")
    expected = prepare(fresh, split_materials(files, fresh.seed, fresh.split), files).truth
    torch.testing.assert_close(truths[1], expected)
    assert not torch.allclose(truths[0], truths[1])


def test_the_frequency_loss_does_not_depend_on_the_band_limit():
    """Parseval on the sphere: the same two smooth materials give about the same L_fre at lmax 15
    and 31 (the old mean over (lmax + 1)² coefficients fell by 4× from one to the other)."""
    valid = merl_above_horizon().reshape(-1)
    values = []
    for lmax in (15, 31):
        config = FrequencyLossConfig(lmax=lmax, slices=(0, 20, 40))
        true = torch.from_numpy(FrequencyTruth(config).coefficients(table_of(smooth_params(0)), valid))[None]
        values.append(float(FrequencyLoss(config).to(torch.float64)(smooth_params(1), true.to(torch.float64))))
    assert values[1] == pytest.approx(values[0], rel=0.1)


def test_spectral_distance_is_the_mean_squared_difference_on_the_sphere():
    """A constant c on the sphere has coefficient c·√(4π) at l = 0: its distance to 0 is c²."""
    c = 0.3
    coefficients = np.zeros((2, 16))
    coefficients[:, 0] = c * np.sqrt(4 * np.pi)
    assert spectral_distance(coefficients, np.zeros_like(coefficients)) == pytest.approx(c**2)


def test_hyperbrdf_weight_penalty_is_the_mean_over_all_weights():
    params = [torch.full((2, 4, 6), 1.0), torch.full((2, 4), 3.0)]
    assert float(weight_penalty(params, "all")) == pytest.approx((48 * 1 + 8 * 9) / 56)
    assert float(weight_penalty(params)) == pytest.approx(1 + 9)  # ours: Σ of the per-tensor means
