"""`frenbrdf fit-decoder` (:mod:`frenbrdf.training.decoder_fit`): a trained run's decoder fitted further with each
training material's latent free, written as a run folder by the output rule."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf import cli
from frenbrdf.exceptions import TrainingDiverged
from frenbrdf.training import decoder_fit, train
from frenbrdf.training.augment import TABLE, BatchDrawer
from frenbrdf.training.decoder_fit import DecoderFitConfig, fit_decoder

from .conftest import tiny


@pytest.fixture(scope="module")
def source_run(toy_materials, tmp_path_factory):
    """A tiny trained run (8 toy tables: 5 train, 1 validates)."""
    return train(tiny("nbrdf", toy_materials, tmp_path_factory.mktemp("fit") / "run", epochs=2)).path


def state(path):
    return frenbrdf.Model.load(path).network.state_dict()


def test_the_fit_lowers_the_training_loss_changes_only_the_decoder_and_reads_as_a_run(source_run, tmp_path):
    out = fit_decoder(source_run, tmp_path / "fitted", DecoderFitConfig(epochs=40, decoder_lr=1e-3, latent_lr=1e-2))
    record = json.loads((out / "decoder-fit.json").read_text())
    losses = [entry["train_rec"] for entry in record["history"]]
    assert len(losses) == 40 and np.mean(losses[-5:]) < 0.8 * np.mean(losses[:5])
    before, after = state(source_run), state(out)
    for name, value in after.items():
        same = torch.equal(value, before[name])
        assert same == name.startswith("encoder."), name  # the encoder kept, every decoder tensor moved
    latents = np.load(out / "latents.npz")
    split = json.loads((source_run / "split.json").read_text())
    assert list(latents["names"]) == split["train"] and latents["latents"].shape == (len(split["train"]), 8)
    assert np.isfinite(latents["latents"]).all()
    # The fitted run is read like any other: a reconstruction with `latent` from the samples of a table.
    model = frenbrdf.Model.load(out)
    rng = np.random.default_rng(0)
    wi, wo = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in np.abs(rng.normal(size=(2, 500, 3))))
    result = model.reconstruct(rng.uniform(0.05, 0.5, (500, 3)), (wi, wo), refine="latent")
    assert np.isfinite(result.losses["latent"])


def test_with_an_encoder_weight_the_encoder_fits_along_and_its_decoding_improves(source_run, tmp_path):
    out = fit_decoder(source_run, tmp_path / "joint",
                      DecoderFitConfig(epochs=40, decoder_lr=1e-3, latent_lr=1e-2, encoder_weight=1.0))
    history = json.loads((out / "decoder-fit.json").read_text())["history"]
    encoded = [entry["train_rec_encoder"] for entry in history]
    assert np.mean(encoded[-5:]) < 0.8 * np.mean(encoded[:5])
    before, after = state(source_run), state(out)
    moved = {name for name, value in after.items() if not torch.equal(value, before[name])}
    assert any(name.startswith("encoder.") for name in moved) and any(name.startswith("decoder.") for name in moved)


def test_with_the_encoder_rate_zero_the_encoder_is_kept_and_read(source_run, tmp_path):
    out = fit_decoder(source_run, tmp_path / "anchored", DecoderFitConfig(epochs=2, encoder_weight=1.0, encoder_lr=0.0))
    assert "train_rec_encoder" in json.loads((out / "decoder-fit.json").read_text())["history"][0]
    before, after = state(source_run), state(out)
    assert all(torch.equal(value, before[name]) for name, value in after.items() if name.startswith("encoder."))


def test_with_encoder_augment_the_encoder_term_reads_the_runs_augmented_materials(toy_materials, source_run,
                                                                                  tmp_path, monkeypatch):
    augmented = train(tiny("nbrdf", toy_materials, tmp_path / "augmented-run", epochs=1,
                           augment={"mix": 0.4, "gain": 0.4, "hue_turn": 0.5, "preset": "custom"})).path
    drawn, read = [], []
    original_draw, original_terms = BatchDrawer.draw, decoder_fit.loss_terms

    def draw(self, batch, generator):
        result = original_draw(self, batch, generator)
        drawn.append(result)
        return result

    def terms(network, frequency, loss, context, query, *args):
        read.append((context, query))
        return original_terms(network, frequency, loss, context, query, *args)

    monkeypatch.setattr(BatchDrawer, "draw", draw)
    monkeypatch.setattr(decoder_fit, "loss_terms", terms)
    config = DecoderFitConfig(epochs=3, encoder_weight=1.0, encoder_lr=0.0, encoder_augment=True)
    out = fit_decoder(augmented, tmp_path / "fitted", config)
    history = json.loads((out / "decoder-fit.json").read_text())["history"]
    assert len(history) == 3 and all(np.isfinite(entry["train_rec_encoder"]) for entry in history)
    n_train = len(json.loads((augmented / "split.json").read_text())["train"])
    assert len(drawn) == 3 * (n_train // 2)  # one draw a step (batches of 2), some of it augmented
    assert any((batch.roles != TABLE).any() for batch in drawn)
    # The encoder term reads exactly what was drawn, context and query.
    assert len(read) == len(drawn)
    assert all(c is batch.context and q is batch.query for (c, q), batch in zip(read, drawn, strict=True))
    before, after = state(augmented), state(out)
    assert all(torch.equal(value, before[name]) for name, value in after.items() if name.startswith("encoder."))
    # A run that trained on its tables as they are has nothing to draw them through: refused before any work.
    with pytest.raises(ValueError, match="trained without augmentations"):
        fit_decoder(source_run, tmp_path / "refused", config)
    assert not (tmp_path / "refused").exists()


def test_the_same_seed_fits_the_same_decoder(source_run, tmp_path):
    config = DecoderFitConfig(epochs=2, seed=3)
    first, second = (fit_decoder(source_run, tmp_path / name, config) for name in ("a", "b"))
    for name, value in state(first).items():
        torch.testing.assert_close(value, state(second)[name])


def test_outputs_follow_the_output_rule(source_run, tmp_path):
    config = DecoderFitConfig(epochs=1)
    with pytest.raises(ValueError, match="input"):
        fit_decoder(source_run, source_run, config)
    user = tmp_path / "user"
    user.mkdir()
    (user / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="notes.txt"):
        fit_decoder(source_run, user, config)
    out = fit_decoder(source_run, tmp_path / "fitted", config)
    with pytest.raises(ValueError, match="--out"):  # an earlier fit is replaced only when asked
        fit_decoder(source_run, out, config)
    (out / "mine.txt").write_text("kept")
    fit_decoder(source_run, out, config, overwrite=True)
    assert (out / "mine.txt").read_text() == "kept" and (out / "best.pt").is_file()


def test_a_folder_that_is_no_trained_run_or_lost_its_data_is_refused_by_name(source_run, tmp_path):
    with pytest.raises(FileNotFoundError, match="config.json"):
        fit_decoder(tmp_path, tmp_path / "out")
    partial = tmp_path / "partial"
    shutil.copytree(source_run, partial)
    (partial / "best.pt").unlink()
    with pytest.raises(ValueError, match="best.pt"):
        fit_decoder(partial, tmp_path / "out")
    moved = tmp_path / "moved"
    shutil.copytree(source_run, moved)
    config = json.loads((moved / "config.json").read_text())
    data = tmp_path / "data"
    shutil.copytree(config["data"], data)
    lost = json.loads((moved / "split.json").read_text())["train"][0]
    (data / f"{lost}.binary").unlink()
    (moved / "config.json").write_text(json.dumps(config | {"data": str(data)}))
    with pytest.raises(ValueError, match=lost):
        fit_decoder(moved, tmp_path / "out")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("bad", [dict(epochs=0), dict(decoder_lr=float("nan")), dict(latent_lr=0.0),
                                 dict(decoder_lr=2.0), dict(seed=-1), dict(encoder_weight=-1.0),
                                 dict(encoder_weight=float("nan")), dict(encoder_weight=1e3), dict(encoder_lr=-1e-4),
                                 dict(encoder_lr=float("inf")), dict(encoder_augment=True)])
def test_bad_settings_are_refused_by_name(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        DecoderFitConfig(**bad)


def test_a_diverging_fit_writes_nothing(source_run, tmp_path, monkeypatch):
    monkeypatch.setattr("frenbrdf.training.step.reconstruction_loss",
                        lambda *args, **kwargs: torch.tensor(float("nan"), requires_grad=True))
    with pytest.raises(TrainingDiverged, match="decoder_lr"):
        fit_decoder(source_run, tmp_path / "out", DecoderFitConfig(epochs=1))
    assert not (tmp_path / "out").exists()


def test_the_command_line(source_run, tmp_path, capsys):
    out = tmp_path / "fitted"
    assert cli.main(["fit-decoder", str(source_run), "--out", str(out), "--epochs", "1", "--quiet"]) == 0
    assert "--decoder-from" in capsys.readouterr().out and (out / "best.pt").is_file()
    for option, value in (("--decoder-lr", "nan"), ("--latent-lr", "0"), ("--epochs", "0"), ("--encoder-weight", "-1"),
                          ("--encoder-lr", "-1")):
        with pytest.raises(SystemExit):
            cli.main(["fit-decoder", str(source_run), "--out", str(tmp_path / "x"), option, value])
        assert option in capsys.readouterr().err
    # --encoder-augment without --encoder-weight has nothing to act on: refused by name, nothing written.
    with pytest.raises(SystemExit):
        cli.main(["fit-decoder", str(source_run), "--out", str(tmp_path / "y"), "--encoder-augment"])
    assert "encoder_augment needs encoder_weight" in capsys.readouterr().err and not (tmp_path / "y").exists()
