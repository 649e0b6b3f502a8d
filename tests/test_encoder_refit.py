"""An encoder with DeepSets' ρ (``EncoderConfig.pooled``) and a run that trains only an encoder for a trained,
frozen decoder (``TrainConfig.decoder_from``)."""

import json

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf.models.autoencoder import AutoEncoder, ModelConfig
from frenbrdf.models.encoder import EncoderConfig, SetEncoder
from frenbrdf.training import train

from .conftest import tiny


def test_a_pooled_encoder_is_order_invariant_and_not_a_mean_of_codes():
    torch.manual_seed(0)
    encoder = SetEncoder(EncoderConfig(hidden=(16, 16), latent=4, pooled=(8,)))
    samples = torch.cat([torch.randn(2, 25, 9) + 3, torch.randn(2, 25, 9) - 3], dim=1)  # two unlike halves
    z = encoder(samples)
    assert z.shape == (2, 4)
    torch.testing.assert_close(encoder(samples[:, torch.randperm(50)]), z)
    # Without ρ, z of a set is the mean of the codes of its halves; with ρ it is not.
    halves = (encoder(samples[:, :25]) + encoder(samples[:, 25:])) / 2
    assert not torch.allclose(halves, z, atol=1e-3)
    plain = SetEncoder(EncoderConfig(hidden=(16, 16), latent=4))
    torch.testing.assert_close((plain(samples[:, :25]) + plain(samples[:, 25:])) / 2, plain(samples))


def test_the_paper_encoder_keeps_its_state_dict_keys_and_parameter_count():
    config = ModelConfig()
    keys = [k for k in AutoEncoder(config).state_dict() if k.startswith("encoder.")]
    assert keys == [f"encoder.per_sample.{i}.{p}" for i in (0, 2, 4, 6) for p in ("weight", "bias")]
    pooled = ModelConfig(encoder=EncoderConfig(pooled=(128,)))
    attention = ModelConfig(encoder=EncoderConfig(pooling="attention"),
                            extra_encoders=(EncoderConfig(pooled=(64,), pooling="attention", attention_heads=8),))
    for cfg in (config, pooled, attention):
        assert cfg.n_parameters == sum(p.numel() for p in AutoEncoder(cfg).parameters())


@pytest.mark.parametrize("bad", [dict(pooled=(0,)), dict(pooled=(8,), hidden=()), dict(pooled=(8,) * 17)])
def test_bad_pooled_encoder_configs_are_refused_by_name(bad):
    with pytest.raises(ValueError, match="pooled|ρ"):
        EncoderConfig(**bad)


def test_encoding_a_large_set_in_chunks_equals_encoding_it_whole(toy_materials, tmp_path, monkeypatch):
    cfg = tiny("nbrdf", toy_materials, tmp_path / "run", epochs=1)
    cfg.model.encoder.pooled = (16,)
    model = frenbrdf.Model.load(train(cfg).path)
    rng = np.random.default_rng(0)
    wi, wo = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in np.abs(rng.normal(size=(2, 3000, 3))))
    values = rng.uniform(0.01, 1.0, (3000, 3))
    whole = model.encode(values, (wi, wo))
    monkeypatch.setattr("frenbrdf.models.autoencoder.ENCODE_CHUNK", 700)
    np.testing.assert_allclose(model.encode(values, (wi, wo)), whole, rtol=1e-5, atol=1e-6)


def test_an_encoder_trained_for_a_frozen_decoder_keeps_that_decoder_and_mapping(toy_materials, tmp_path):
    source = train(tiny("frenbrdf", toy_materials, tmp_path / "source", epochs=2))
    cfg = tiny("frenbrdf", toy_materials, tmp_path / "refit", epochs=6, decoder_from=str(source.path))
    cfg.model.encoder.pooled = (16,)
    refit = train(cfg)
    old, new = frenbrdf.Model.load(source.path), frenbrdf.Model.load(refit.path)
    for name, weight in old.network.decoder.state_dict().items():
        torch.testing.assert_close(new.network.decoder.state_dict()[name], weight)
    np.testing.assert_array_equal(new.mapping.state()["reference"], old.mapping.state()["reference"])
    untrained, best = refit.history[0], refit.best  # epoch −1: the new encoder before any step
    assert best["val_rec"] < untrained["val_rec"] - 1e-3  # the encoder learned
    assert new.config.encoder.pooled == (16,)


@pytest.mark.parametrize("option", ["decoder_from", "init_from"])
def test_the_run_a_training_starts_from_is_an_input_never_its_output(toy_materials, tmp_path, option):
    source = train(tiny("frenbrdf", toy_materials, tmp_path / "source", epochs=1))
    before = {p.name: p.read_bytes() for p in source.path.iterdir()}
    for given in (source.path, source.path / "best.pt"):  # the run, or one of its checkpoints
        cfg = tiny("frenbrdf", toy_materials, source.path, epochs=1, **{option: str(given)})
        with pytest.raises(ValueError, match="is the input"):
            train(cfg, overwrite=True)
    assert {p.name: p.read_bytes() for p in source.path.iterdir()} == before


def test_a_decoder_of_another_shape_is_refused_before_training(toy_materials, tmp_path):
    source = train(tiny("nbrdf", toy_materials, tmp_path / "source", epochs=1))
    cfg = tiny("nbrdf", toy_materials, tmp_path / "refit", decoder_from=str(source.path))
    cfg.model.nbrdf.hidden = (8, 8)
    with pytest.raises(ValueError, match="differs from this run's in nbrdf"):
        train(cfg)
    assert not (tmp_path / "refit" / "config.json").exists()


def test_a_fine_tune_starts_where_its_source_ended_and_trains_everything(toy_materials, tmp_path):
    source = train(tiny("frenbrdf", toy_materials, tmp_path / "source", epochs=2))
    tuned = train(tiny("frenbrdf", toy_materials, tmp_path / "tuned", epochs=2, init_from=str(source.path)))
    assert tuned.history[0]["val_rec"] == pytest.approx(source.best["val_rec"], rel=1e-6)  # before its first step
    old, new = frenbrdf.Model.load(source.path), frenbrdf.Model.load(tuned.path)
    np.testing.assert_array_equal(new.mapping.state()["reference"], old.mapping.state()["reference"])
    changed = [not torch.equal(new.network.decoder.state_dict()[k], w) for k, w in old.network.decoder.state_dict().items()]
    assert any(changed)


def test_init_from_needs_the_same_model(toy_materials, tmp_path):
    source = train(tiny("nbrdf", toy_materials, tmp_path / "source", epochs=1))
    cfg = tiny("nbrdf", toy_materials, tmp_path / "tuned", init_from=str(source.path))
    cfg.model.encoder.pooled = (8,)
    with pytest.raises(ValueError, match="init_from .* differs from this run's in encoder"):
        train(cfg)


def test_init_from_with_decoder_from_starts_the_encoder_from_one_and_freezes_the_others_decoder(toy_materials,
                                                                                                tmp_path):
    decoder_source = train(tiny("nbrdf", toy_materials, tmp_path / "decoder", epochs=1))
    encoder_source = train(tiny("nbrdf", toy_materials, tmp_path / "encoder", epochs=1, seed=3,
                                decoder_from=str(decoder_source.path)))
    cfg = tiny("nbrdf", toy_materials, tmp_path / "both", epochs=1, lr=1e-12, seed=5,
               decoder_from=str(decoder_source.path), init_from=str(encoder_source.path))
    both = frenbrdf.Model.load(train(cfg).path)  # lr 1e-12: every weight stays where it started
    for part, source in (("encoder", encoder_source), ("decoder", decoder_source)):
        expected = getattr(frenbrdf.Model.load(source.path).network, part).state_dict()
        for name, tensor in getattr(both.network, part).state_dict().items():
            torch.testing.assert_close(tensor, expected[name], msg=f"{part}.{name}")
    cfg = tiny("nbrdf", toy_materials, tmp_path / "other", decoder_from=str(decoder_source.path),
               init_from=str(encoder_source.path))
    cfg.model.encoder.pooling, cfg.model.encoder.attention_heads = "attention", 2
    with pytest.raises(ValueError, match="init_from .* differs from this run's in .*attention"):
        train(cfg)


def test_an_encoder_mean_averages_its_members_and_packs_and_loads(toy_materials, tmp_path):
    from frenbrdf.models import pretrained

    from .conftest import script_module

    base_run = train(tiny("nbrdf", toy_materials, tmp_path / "base", epochs=1))
    packed = tmp_path / "packed"
    pretrained.pack_pretrained(base_run.path, packed, half=False)
    cfg = tiny("nbrdf", toy_materials, tmp_path / "member", epochs=1, decoder_from=str(packed))
    cfg.model.encoder.pooled = (16,)
    member = train(cfg)
    checkpoint, mapping, _ = script_module("pack_encoder_mean").assemble(str(packed), [str(member.path)])
    mean = frenbrdf.Model.from_checkpoint(checkpoint, mapping)
    assert mean.config.extra_encoders[0].pooled == (16,)
    rng = np.random.default_rng(1)
    wi, wo = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in np.abs(rng.normal(size=(2, 500, 3))))
    values = rng.uniform(0.01, 1.0, (500, 3))
    parts = [frenbrdf.Model.load(base_run.path), frenbrdf.Model.load(member.path)]
    expected = np.mean([m.encode(values, (wi, wo)) for m in parts], axis=0)
    np.testing.assert_allclose(mean.encode(values, (wi, wo)), expected, rtol=1e-5, atol=1e-6)
    pretrained.pack_checkpoint(checkpoint, mapping, tmp_path / "mean", half=False)
    reloaded = frenbrdf.models.autoencoder.load_model(tmp_path / "mean")  # a packed folder loads like a run
    np.testing.assert_allclose(reloaded.encode(values, (wi, wo)), expected, rtol=1e-5, atol=1e-6)
    with pytest.raises(ValueError, match="several encoders"):  # it would keep only the first
        script_module("pack_encoder_mean").assemble(str(tmp_path / "mean"), [str(member.path)])
    other = train(tiny("nbrdf", toy_materials, tmp_path / "other", epochs=1, seed=3))  # another decoder
    with pytest.raises(ValueError, match="not the base's"):
        script_module("pack_encoder_mean").assemble(str(packed), [str(other.path)])


def test_an_encoder_mean_without_the_base_encoder_is_the_members_alone(toy_materials, tmp_path):
    from frenbrdf.models import pretrained

    from .conftest import script_module

    base_run = train(tiny("nbrdf", toy_materials, tmp_path / "base", epochs=1))
    packed = tmp_path / "packed"
    pretrained.pack_pretrained(base_run.path, packed, half=False)
    members = [train(tiny("nbrdf", toy_materials, tmp_path / f"member{seed}", epochs=1, seed=seed,
                          decoder_from=str(packed))) for seed in (1, 2)]
    rng = np.random.default_rng(2)
    wi, wo = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in np.abs(rng.normal(size=(2, 400, 3))))
    values = rng.uniform(0.01, 1.0, (400, 3))
    codes = [frenbrdf.Model.load(m.path).encode(values, (wi, wo)) for m in members]
    assemble = script_module("pack_encoder_mean").assemble
    for chosen, expected in (([members[0]], codes[0]), (members, np.mean(codes, axis=0))):
        checkpoint, mapping, _ = assemble(str(packed), [str(m.path) for m in chosen], base_encoder=False)
        model = frenbrdf.Model.from_checkpoint(checkpoint, mapping)
        assert len(model.config.encoders) == len(chosen)
        np.testing.assert_allclose(model.encode(values, (wi, wo)), expected, rtol=1e-5, atol=1e-6)
    with pytest.raises(ValueError, match="no encoder"):
        assemble(str(packed), [], base_encoder=False)


def test_a_best_fit_choice_takes_the_latent_whose_decoding_fits_the_samples_best(toy_materials, tmp_path):
    from frenbrdf.io.sampling import draw_samples
    from frenbrdf.models import pretrained
    from frenbrdf.models.reconstruct import RefineConfig, _starts, reconstruct

    from .conftest import script_module

    base_run = train(tiny("nbrdf", toy_materials, tmp_path / "base", epochs=2))
    packed = tmp_path / "packed"
    pretrained.pack_pretrained(base_run.path, packed, half=False)
    members = [str(train(tiny("nbrdf", toy_materials, tmp_path / f"member{seed}", epochs=1 + seed, seed=seed,
                              decoder_from=str(packed))).path) for seed in (1, 2)]
    assemble = script_module("pack_encoder_mean").assemble
    best_fit = frenbrdf.Model.from_checkpoint(*assemble(str(packed), members, choice="best-fit")[:2])
    mean = frenbrdf.Model.from_checkpoint(*assemble(str(packed), members)[:2])
    assert best_fit.config.encoder_choice == "best-fit" and mean.config.encoder_choice == "mean"
    parts = [frenbrdf.Model.load(base_run.path), *map(frenbrdf.Model.load, members)]
    truth = frenbrdf.read_merl(sorted(toy_materials.glob("*.binary"))[0])
    drawn = draw_samples(truth, samples=800, seed=3)
    values, directions = drawn.values, (drawn.wi, drawn.wo)
    latents = [m.encode(values, directions) for m in parts]
    losses = [reconstruct(m, values, directions, refine="none").losses["encode"] for m in parts]
    assert len({round(loss, 6) for loss in losses}) == 3  # the three encoders disagree: the choice matters
    np.testing.assert_allclose(best_fit.encode(values, directions), latents[int(np.argmin(losses))], rtol=1e-5,
                               atol=1e-6)
    np.testing.assert_allclose(mean.encode(values, directions), np.mean(latents, axis=0), rtol=1e-5, atol=1e-6)
    refined = best_fit.reconstruct(values, directions, refine="none")  # refinement starts from the chosen latent
    assert refined.losses["encode"] == pytest.approx(min(losses), rel=1e-4)

    # stage 1 from several encoders' latents: the chosen one first, then by fit; the best fit after the steps kept
    order = [int(i) for i in np.argsort(losses, kind="stable")]
    starts = [z[0].numpy() for z in _starts(best_fit.encoding(values, directions), 3)]
    for start, index in zip(starts, order, strict=True):
        np.testing.assert_allclose(start, latents[index], rtol=1e-5, atol=1e-6)
    single = [best_fit.reconstruct(values, directions, refine=RefineConfig(latent_steps=4, latent_lr=0.05, starts=n))
              for n in (1, 3)]
    assert single[1].steps["latent"] == 3 * single[0].steps["latent"] == 12
    assert single[1].losses["latent"] <= single[0].losses["latent"]
    # What chose z is kept (reconstruction.json's "encoder"): which encoder and every one's loss.
    chosen = int(np.argmin(losses))
    assert refined.encoder["chosen"] == chosen and refined.encoder["pooling"] == "mean"
    np.testing.assert_allclose(refined.encoder["losses"], losses, rtol=1e-4)
    np.testing.assert_allclose(best_fit.encoding(values, directions).latents, latents, rtol=1e-5, atol=1e-6)
    assert mean.reconstruct(values, directions, refine="none").summary()["encoder"] == {"encoders": 3,
                                                                                       "choice": "mean"}


def test_an_unknown_encoder_choice_is_refused_by_name():
    with pytest.raises(ValueError, match="encoder_choice must be one of"):
        ModelConfig(encoder_choice="vote")


def test_an_attention_member_packs_beside_a_mean_base_and_the_card_names_the_poolings(toy_materials, tmp_path):
    from frenbrdf.models import pretrained

    from .conftest import script_module

    base_run = train(tiny("nbrdf", toy_materials, tmp_path / "base", epochs=1))
    packed = tmp_path / "packed"
    pretrained.pack_pretrained(base_run.path, packed, half=False)
    cfg = tiny("nbrdf", toy_materials, tmp_path / "member", epochs=1, seed=1, decoder_from=str(packed))
    cfg.model.encoder.pooling = "attention"
    member = train(cfg)
    pack = script_module("pack_encoder_mean")
    checkpoint, mapping, _ = pack.assemble(str(packed), [str(member.path)], choice="best-fit")
    model = frenbrdf.Model.from_checkpoint(checkpoint, mapping)
    assert [e.pooling for e in model.network.encoder.encoders()] == ["mean", "attention"]
    assert pack.poolings(checkpoint) == ["mean", "attention"]
    rng = np.random.default_rng(4)
    wi, wo = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in np.abs(rng.normal(size=(2, 300, 3))))
    values = rng.uniform(0.01, 1.0, (300, 3))
    choices = [frenbrdf.Model.load(run).encode(values, (wi, wo)) for run in (base_run.path, member.path)]
    assert any(np.allclose(model.encode(values, (wi, wo)), z, rtol=1e-5, atol=1e-6) for z in choices)
    text = script_module("train_shipped_model").encoders_text
    card = {"encoders": {"members": ["m"], "choice": "best-fit", "command": "pack", "poolings": ["mean", "attention"]}}
    assert "pooled by mean (1), attention (1)" in text(card)
    del card["encoders"]["poolings"]  # a card from before version 6: every encoder took the mean
    assert "pooled by" not in text(card)
    card["encoders"]["training_config"] = {"sampling": {"patterns": {"uniform": 1.0}}}  # before version 8: one config
    assert 'with the sampling `{"patterns": {"uniform": 1.0}}`;' in text(card)
    own = pack.member_sampling(str(member.path))  # what the member's run trained with
    assert own and own == json.loads((member.path / "config.json").read_text())["sampling"]
    card["encoders"]["samplings"] = [own, own, {"patterns": {"specular": 1.0}}]
    assert f'with the samplings `{json.dumps(own)}` (2); `{{"patterns": {{"specular": 1.0}}}}` (1);' in text(card)
