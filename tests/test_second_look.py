"""The encoder's second look (frenbrdf.models.second_look): a start that is the first look, parts that add up to
the whole set, and a model that carries one through its config and checkpoint."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import torch

from frenbrdf.configs import from_dict, to_dict
from frenbrdf.models import AutoEncoder, DecoderConfig, EncoderConfig, Model, ModelConfig, NBRDFConfig
from frenbrdf.models.losses import samples_loss
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.models.nbrdf import mapped_samples
from frenbrdf.models.second_look import LookMean, SecondLook, SecondLookConfig

from .conftest import unit_vectors

LATENT = 4


SMALL_LOOK = SecondLookConfig((16,), (16,))


def small_config(look: SecondLookConfig | None = SMALL_LOOK) -> ModelConfig:
    return ModelConfig(nbrdf=NBRDFConfig((8,)), encoder=EncoderConfig((16,), LATENT), decoder=DecoderConfig((16,)),
                       second_look=look)


def samples(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    wi, wo = unit_vectors(rng, n), unit_vectors(rng, n)
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    return rng.uniform(0, 1, (n, 3)), (wi, wo)


def stirred(look: SecondLook, seed: int = 0) -> SecondLook:
    """The look with its zero last layer given random weights, as training would."""
    generator = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for p in look.after_pool[-1].parameters():
            p.copy_(0.1 * torch.randn(p.shape, generator=generator))
    return look


def batch(n: int, b: int = 2, seed: int = 0):
    generator = torch.Generator().manual_seed(seed)
    coords, values = torch.rand(b, n, 6, generator=generator), torch.rand(b, n, 3, generator=generator)
    return coords, values, torch.rand(b, n, generator=generator), torch.randn(b, LATENT, generator=generator)


def test_an_untrained_second_look_is_the_first():
    network = AutoEncoder(small_config())
    coords, values, cos_in, z1 = batch(50)
    assert torch.equal(network.second_look(coords, values, cos_in, z1, network.decoder), z1)


def test_parts_give_the_whole_set():
    network = AutoEncoder(small_config())
    look = stirred(network.second_look)
    coords, values, cos_in, z1 = batch(230)
    whole = look(coords, values, cos_in, z1, network.decoder)
    assert not torch.allclose(whole, z1)  # the stirred look moves z
    parts = look(coords, values, cos_in, z1, network.decoder, chunk=50)  # 4 parts of 50 and one of 30
    torch.testing.assert_close(parts, whole, rtol=1e-5, atol=1e-6)


def test_it_learns_and_leaves_the_decoder_and_first_guess_alone():
    network = AutoEncoder(small_config())
    network.decoder.requires_grad_(False)
    coords, values, cos_in, z1 = batch(40)
    z1.requires_grad_(True)
    z = network.second_look(coords, values, cos_in, z1.detach(), network.decoder)
    z.square().sum().backward()
    assert network.second_look.after_pool[-1].weight.grad.abs().sum() > 0
    assert z1.grad is None and all(p.grad is None for p in network.decoder.parameters())


def test_a_model_with_a_second_look_encodes_through_it():
    config = small_config()
    network = AutoEncoder(config)
    stirred(network.second_look)
    model = Model(network, LogRelativeMapping(np.full(3, 0.1)), config)
    values, directions = samples(200)
    encoding = model.encoding(values, directions)
    assert encoding.first_look is not None and not np.allclose(encoding.z, encoding.first_look)
    assert encoding.summary()["second_look"] is True
    np.testing.assert_allclose(model.encode(values, directions), encoding.z)
    first = Model(AutoEncoder(small_config(None)), model.mapping, small_config(None))
    first.network.load_state_dict({k: v for k, v in network.state_dict().items() if not k.startswith("second_look")})
    np.testing.assert_allclose(first.encode(values, directions), encoding.first_look, rtol=1e-6)


def test_more_looks_start_each_from_the_last():
    """``steps`` looks: each reads the samples again from the z the one before gave, and a config of one step is
    the model as it was."""
    values, directions = samples(200)
    network = AutoEncoder(small_config())
    stirred(network.second_look)
    models = {steps: Model(network, LogRelativeMapping(np.full(3, 0.1)),
                           small_config(dataclasses.replace(SMALL_LOOK, steps=steps))) for steps in (1, 2, 3)}
    encodings = {steps: model.encoding(values, directions) for steps, model in models.items()}
    mapped, coords, cos_in = (torch.from_numpy(a.astype(np.float32))[None]
                              for a in mapped_samples(models[1].mapping, values, directions))
    z = torch.from_numpy(encodings[1].first_look.astype(np.float32))[None]
    with torch.no_grad():
        for steps in (1, 2, 3):
            z = network.second_look(coords, mapped, cos_in, z, network.decoder)
            np.testing.assert_allclose(encodings[steps].z, z[0].numpy(), rtol=1e-5, atol=1e-6)
            np.testing.assert_array_equal(encodings[steps].first_look, encodings[1].first_look)
            assert encodings[steps].summary()["looks"] == steps
    assert not np.allclose(encodings[2].z, encodings[1].z)


def test_a_best_fit_choice_keeps_the_z_that_fits_the_samples_best():
    """``choice="best-fit"``: of the encoders' z and each look's, the one whose decoding has the lowest samples'
    loss, with the losses and the looks that led to it in the encoding and its summary."""
    values, directions = samples(200)
    network = AutoEncoder(small_config())
    stirred(network.second_look, seed=3)
    mapping = LogRelativeMapping(np.full(3, 0.1))
    last = Model(network, mapping, small_config(dataclasses.replace(SMALL_LOOK, steps=3))).encoding(values, directions)
    best = Model(network, mapping, small_config(dataclasses.replace(SMALL_LOOK, steps=3, choice="best-fit")))
    encoding = best.encoding(values, directions)
    mapped, coords, cos_in = (torch.from_numpy(a.astype(np.float32))[None]
                              for a in mapped_samples(mapping, values, directions))
    zs = [torch.from_numpy(encoding.first_look.astype(np.float32))[None]]
    with torch.no_grad():
        for _ in range(3):
            zs.append(network.second_look(coords, mapped, cos_in, zs[-1], network.decoder))
        losses = [samples_loss(network.decoder(z), coords, mapped, cos_in) for z in zs]
    assert encoding.look_losses is not None and len(encoding.look_losses) == 4
    np.testing.assert_allclose(encoding.look_losses, losses, rtol=1e-5)
    assert encoding.looks == int(np.argmin(losses))
    np.testing.assert_allclose(encoding.z, zs[encoding.looks][0].numpy(), rtol=1e-5, atol=1e-6)
    assert encoding.summary()["looks"] == encoding.looks and len(encoding.summary()["look_losses"]) == 4
    np.testing.assert_allclose(last.z, zs[3][0].numpy(), rtol=1e-5, atol=1e-6)
    assert last.look_losses is None and "look_losses" not in last.summary()


@pytest.mark.parametrize("steps", [0, -1, 17, 1.5, True, "2"])
def test_a_wrong_number_of_looks_is_refused(steps):
    with pytest.raises(ValueError, match="second look steps"):
        SecondLookConfig(steps=steps)


@pytest.mark.parametrize("members", [0, 9, 2.0, False])
def test_a_wrong_number_of_members_is_refused(members):
    with pytest.raises(ValueError, match="second look members"):
        SecondLookConfig(members=members)


def test_several_members_answer_from_one_reading_of_the_guess():
    """``members``: z is the mean of each look's answer, and the guess is decoded once for all of them."""
    config = small_config(dataclasses.replace(SMALL_LOOK, members=3))
    network = AutoEncoder(config)
    assert isinstance(network.second_look, LookMean) and config.n_parameters == sum(
        p.numel() for p in network.parameters())
    looks = [stirred(look, seed) for seed, look in enumerate(network.second_look.looks())]
    coords, values, cos_in, z1 = batch(120)
    decodings = []
    network.decoder.register_forward_hook(lambda *_: decodings.append(1))
    z = network.second_look(coords, values, cos_in, z1, network.decoder, chunk=50)
    assert len(decodings) == 1
    alone = torch.stack([look(coords, values, cos_in, z1, network.decoder) for look in looks]).mean(dim=0)
    torch.testing.assert_close(z, alone, rtol=1e-5, atol=1e-6)
    assert from_dict(ModelConfig, to_dict(config)) == config


def test_an_unknown_choice_of_look_is_refused():
    with pytest.raises(ValueError, match="second look choice"):
        SecondLookConfig(choice="mean")


def test_the_config_round_trips_and_counts_its_parameters():
    config = small_config()
    assert from_dict(ModelConfig, to_dict(config)) == config
    assert from_dict(SecondLookConfig, {"hidden": [16], "after": [16]}).steps == 1  # version 10's config: one look
    assert from_dict(ModelConfig, to_dict(small_config(None))).second_look is None  # older models: no key, no look
    assert config.n_parameters == sum(p.numel() for p in AutoEncoder(config).parameters())
    with pytest.raises(ValueError, match="second look sizes"):
        SecondLookConfig(hidden=())


def test_the_packer_adds_the_look_with_the_lowest_validation_loss(tmp_path):
    """release/pack_second_look.py: of several look runs the one whose validation loss fell lowest joins the base's
    config and weights; the model it makes corrects its first look; a base with a look already is refused."""
    from frenbrdf.models import pretrained

    from .conftest import script_module

    packer = script_module("pack_second_look")
    config = small_config(None)
    base = Model(AutoEncoder(config), LogRelativeMapping(np.full(3, 0.1)), config)
    checkpoint = {"method": "frenbrdf", "config": json.dumps({"model": to_dict(config)}),
                  "model": base.network.state_dict()}
    pretrained.pack_checkpoint(checkpoint, base.mapping.state(), tmp_path / "base", half=False)
    runs = []
    for seed, losses in ((1, [0.5, 0.3]), (2, [0.4, 0.2])):  # the second run fell lowest
        run = tmp_path / f"look-{seed}"
        run.mkdir()
        look = stirred(SecondLook(LATENT, SMALL_LOOK), seed)
        torch.save({"state": look.state_dict(), "epoch": 1, "config": to_dict(SMALL_LOOK)}, run / "second_look.pt")
        (run / "history.json").write_text(json.dumps([{"val_second": loss} for loss in losses]))
        runs.append(run)
    chosen = packer.best_look(runs)
    assert chosen == runs[1]
    assembled, mapping, card = packer.assemble(str(tmp_path / "base"), [chosen])
    model = Model.from_checkpoint(assembled, mapping)
    assert model.config.second_look == SMALL_LOOK and card["look_epochs"] == [1]
    values, directions = samples(100)
    encoding = model.encoding(values, directions)
    np.testing.assert_allclose(encoding.first_look, base.encode(values, directions), rtol=1e-5, atol=1e-6)
    assert not np.allclose(encoding.z, encoding.first_look)
    twice, _, _ = packer.assemble(str(tmp_path / "base"), [chosen], steps=2)
    assert json.loads(twice["config"])["model"]["second_look"]["steps"] == 2
    pretrained.pack_checkpoint(assembled, mapping, tmp_path / "with-look", half=False)
    with pytest.raises(ValueError, match="has a second look already"):
        packer.assemble(str(tmp_path / "with-look"), [chosen])
    with pytest.raises(ValueError, match="has a second look"):  # new encoders would not be the look's
        script_module("pack_encoder_mean").assemble(str(tmp_path / "with-look"), [], base_encoder=False)
    # --mean: every look packed, their answers averaged
    both, mapping, card = packer.assemble(str(tmp_path / "base"), runs, steps=2)
    averaged = Model.from_checkpoint(both, mapping)
    assert averaged.config.second_look == dataclasses.replace(SMALL_LOOK, steps=2, members=2)
    assert card["look_epochs"] == [1, 1]
    separately = [Model.from_checkpoint(packer.assemble(str(tmp_path / "base"), [run])[0], mapping) for run in runs]
    mapped, coords, cos_in = (torch.from_numpy(a.astype(np.float32))[None]
                              for a in mapped_samples(averaged.mapping, values, directions))
    z = torch.from_numpy(encoding.first_look.astype(np.float32))[None]
    with torch.no_grad():
        for _ in range(2):
            z = torch.stack([one.network.second_look(coords, mapped, cos_in, z, one.network.decoder)
                             for one in separately]).mean(dim=0)
    np.testing.assert_allclose(averaged.encode(values, directions), z[0].numpy(), rtol=1e-5, atol=1e-6)
    wider = tmp_path / "look-wider"
    wider.mkdir()
    other = SecondLookConfig((16,), (8,))
    torch.save({"state": SecondLook(LATENT, other).state_dict(), "epoch": 1, "config": to_dict(other)},
               wider / "second_look.pt")
    with pytest.raises(ValueError, match="different sizes"):
        packer.assemble(str(tmp_path / "base"), [runs[0], wider])
    with pytest.raises(ValueError, match="given twice"):
        packer.assemble(str(tmp_path / "base"), [runs[0], runs[0]])
    # a config of two looks with one look's weights: named, not a crash
    mismatched = {**assembled, "config": both["config"]}
    with pytest.raises(ValueError, match="do not match its model config: second_look"):
        Model.from_checkpoint(mismatched, mapping)
