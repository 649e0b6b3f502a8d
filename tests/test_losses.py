"""Losses: L_rec and the frequency-rectified loss."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from frenbrdf.models.nbrdf import bin_geometry
from frenbrdf.losses import FrequencyLoss, FrequencyLossConfig, FrequencyTruth, reconstruction_loss
from frenbrdf.merl import merl_above_horizon
from frenbrdf.models import NBRDFConfig, nbrdf_forward

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
    files = list(tmp_path.glob("abc-*.npy"))
    assert len(files) == 1
    # A fresh instance reads the file instead of recomputing (a different table proves it).
    again = FrequencyTruth(SMALL, tmp_path).coefficients(table * 0, valid, cache_key="abc")
    np.testing.assert_array_equal(again, first)
    files[0].write_bytes(b"damaged")
    recomputed = FrequencyTruth(SMALL, tmp_path).coefficients(table, valid, cache_key="abc")
    np.testing.assert_allclose(recomputed, first)
