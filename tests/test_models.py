"""Models: batched NBRDF, set encoder, hypernetwork, the public Model API and interpolation."""

from __future__ import annotations

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf.models import (
    NBRDF,
    AutoEncoder,
    DecoderConfig,
    EncoderConfig,
    HyperNetwork,
    Model,
    ModelConfig,
    NBRDFConfig,
    SetEncoder,
    interpolate,
    nbrdf_coordinates,
    nbrdf_forward,
)
from frenbrdf.models.mapping import LogRelativeMapping

from .conftest import unit_vectors


def random_params(config: NBRDFConfig, batch: int, seed: int = 0, dtype=torch.float32) -> list[torch.Tensor]:
    generator = torch.Generator().manual_seed(seed)
    return [torch.randn(batch, *shape, generator=generator, dtype=dtype) * 0.5 for shape in config.shapes()]


def test_nbrdf_sizes_match_the_published_networks():
    assert NBRDFConfig((21, 21)).n_weights == 675
    assert NBRDFConfig((60, 60, 60, 60)).n_weights == 11_583
    with pytest.raises(ValueError, match="positive"):
        NBRDFConfig(())


def test_batched_nbrdf_equals_one_material_at_a_time():
    config = NBRDFConfig((7, 5, 9))
    params = random_params(config, batch=4)
    coords = torch.randn(4, 50, 6)
    batched = nbrdf_forward(params, coords)
    for b in range(4):
        x = coords[b]
        for layer in range(0, len(params), 2):
            x = x @ params[layer][b].T + params[layer + 1][b]
            x = torch.relu(x) if layer < len(params) - 2 else x
        torch.testing.assert_close(batched[b], x)


def test_set_encoder_is_order_invariant_and_takes_any_set_size():
    encoder = SetEncoder(EncoderConfig(hidden=(16, 16), latent=5))
    samples = torch.randn(3, 100, 9)
    z = encoder(samples)
    assert z.shape == (3, 5)
    torch.testing.assert_close(encoder(samples[:, torch.randperm(100)]), z)
    assert encoder(samples[:, :1]).shape == (3, 5)


def test_hypernetwork_heads_produce_every_tensor():
    shapes = NBRDFConfig((8, 8)).shapes()
    z = torch.randn(4, 6)
    spreads, scales = {}, {}
    for last_layer_scale in (0.1, 1.0):
        torch.manual_seed(0)
        decoder = HyperNetwork(6, shapes, DecoderConfig(hidden=(16,), last_layer_scale=last_layer_scale))
        with torch.no_grad():
            params = decoder(z)
        assert [tuple(p.shape) for p in params] == [(4, *s) for s in shapes]
        spreads[last_layer_scale] = max(float((p[0] - p[1]).abs().max()) for p in params)
        scales[last_layer_scale] = max(float(p.abs().max()) for p in params)
    # At 0.1 latents decode to nearly the same NBRDF at first (HyperBRDF's start); at 1, the default,
    # the latent steers the NBRDF from the start (research/colour.md): ten times the spread.
    assert spreads[0.1] < 0.5 * scales[0.1]
    assert spreads[1.0] == pytest.approx(10 * spreads[0.1], rel=1e-4)


def test_nbrdf_object_reflectance_and_merl_table(tmp_path):
    rng = np.random.default_rng(0)
    mapping = LogRelativeMapping(np.full(3, 0.2))
    nbrdf = NBRDF(random_params(NBRDFConfig((8,)), batch=2), mapping)
    with pytest.raises(ValueError, match="holds 2 materials"):
        nbrdf(np.array([0, 0, 1.0]), np.array([0, 0, 1.0]))
    one = nbrdf[1]
    wi, wo = unit_vectors(rng, 1000), unit_vectors(rng, 1000)
    rgb = one(wi, wo)
    below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
    assert rgb.shape == (1000, 3) and np.all(rgb >= 0) and np.all(rgb[below] == 0)
    expected = mapping.inverse(one.mapped(nbrdf_coordinates(wi, wo)), mapping.reference)
    np.testing.assert_allclose(rgb[~below], expected[~below], rtol=1e-6)
    one.to_merl(tmp_path / "decoded.binary")
    table = frenbrdf.read_merl(tmp_path / "decoded.binary")
    assert np.array_equal(frenbrdf.valid_mask(table), frenbrdf.merl_above_horizon())


def test_model_encode_decode_and_input_errors():
    config = ModelConfig(nbrdf=NBRDFConfig((8,)), encoder=EncoderConfig((16,), 4), decoder=DecoderConfig((16,)))
    model = Model(AutoEncoder(config), LogRelativeMapping(np.full(3, 0.1)), config)
    rng = np.random.default_rng(1)
    wi, wo = unit_vectors(rng, 200), unit_vectors(rng, 200)
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    z = model.encode(rng.uniform(0, 1, (200, 3)), (wi, wo))
    assert z.shape == (4,) and np.all(np.isfinite(z))
    assert len(model.decode(np.stack([z, z]))) == 2
    with pytest.raises(ValueError, match="finite and ≥ 0"):
        model.encode(np.full((200, 3), -1.0), (wi, wo))
    with pytest.raises(ValueError, match="shape"):
        model.encode(np.ones((200, 4)), (wi, wo))
    with pytest.raises(ValueError, match="z must be finite"):
        model.decode(np.full(4, np.nan))


@pytest.mark.parametrize("pooling", ["mean", "density"])
def test_model_encode_in_chunks_equals_the_whole_set(monkeypatch, pooling):
    """Sets larger than ENCODE_CHUNK go through the encoder in chunks: the same pooled code (density weights are
    computed over the whole set)."""
    from frenbrdf.models import autoencoder

    config = ModelConfig(nbrdf=NBRDFConfig((8,)), encoder=EncoderConfig((16,), 4, pooling=pooling),
                         decoder=DecoderConfig((16,)))
    model = Model(AutoEncoder(config), LogRelativeMapping(np.full(3, 0.1)), config)
    rng = np.random.default_rng(2)
    wi, wo = unit_vectors(rng, 230), unit_vectors(rng, 230)
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    values = rng.uniform(0, 1, (230, 3))
    whole = model.encode(values, (wi, wo))
    monkeypatch.setattr(autoencoder, "ENCODE_CHUNK", 50)  # 4 chunks of 50 and one of 30
    np.testing.assert_allclose(model.encode(values, (wi, wo)), whole, rtol=1e-5, atol=1e-6)


def test_interpolate_endpoints_and_range():
    z_a, z_b = np.zeros(3), np.arange(3.0)
    np.testing.assert_array_equal(interpolate(z_a, z_b, 0), z_a)
    np.testing.assert_array_equal(interpolate(z_a, z_b, 1), z_b)
    assert interpolate(z_a, z_b, [0, 0.5, 1]).shape == (3, 3)
    with pytest.raises(ValueError, match="extrapolate=True"):
        interpolate(z_a, z_b, 1.5)
    np.testing.assert_array_equal(interpolate(z_a, z_b, 2.0, extrapolate=True), 2 * z_b)


def test_decoded_materials_are_isotropic():
    """Rotating both directions about the normal changes nothing (the networks see φ_h = 0)."""
    rng = np.random.default_rng(5)
    nbrdf = NBRDF(random_params(NBRDFConfig((8,)), batch=1), LogRelativeMapping(np.full(3, 0.2)))
    wi, wo = unit_vectors(rng, 500), unit_vectors(rng, 500)
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    angle = 1.1
    rotation = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    np.testing.assert_allclose(nbrdf(wi @ rotation.T, wo @ rotation.T), nbrdf(wi, wo), rtol=1e-5, atol=1e-7)


def test_nbrdf_coordinates_at_the_bins_are_the_training_inputs():
    from frenbrdf.io.sampling import bin_directions
    from frenbrdf.models.nbrdf import bin_geometry

    bins = np.random.default_rng(0).choice(90 * 90 * 180, 2000)
    wi, wo = bin_directions(bins)
    np.testing.assert_allclose(nbrdf_coordinates(wi, wo), bin_geometry().half_diff[bins].numpy(), atol=1e-6)
