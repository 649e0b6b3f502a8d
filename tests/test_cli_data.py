"""The data commands: synth, import-nbrdf and fit-nbrdf, through the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

import frenbrdf
from frenbrdf import cli
from frenbrdf.data import synth
from frenbrdf.data.fitting import FitConfig, fit_nbrdf
from frenbrdf.io import read_material
from frenbrdf.io.outputs import MARKER

from .conftest import SHARED_DATA, toy_table


def test_synth_command_writes_a_bank(tmp_path, capsys):
    assert cli.main(["synth", str(tmp_path / "bank"), "--n", "3", "--seed", "1", "--quiet"]) == 0
    files = sorted((tmp_path / "bank").glob("*.binary"))
    assert len(files) == 3 and "wrote 3 MERL files" in capsys.readouterr().out
    manifest = json.loads((tmp_path / "bank" / "bank.json").read_text())
    assert manifest["n"] == 3 and manifest["seed"] == 1
    table = frenbrdf.read_merl(files[0])
    assert np.array_equal(frenbrdf.valid_mask(table), frenbrdf.merl_above_horizon())


def test_synth_command_writes_the_features_mix(tmp_path):
    assert cli.main(["synth", str(tmp_path / "bank"), "--n", "5", "--mix", "features", "--quiet"]) == 0
    manifest = json.loads((tmp_path / "bank" / "bank.json").read_text())
    assert manifest["mix"] == "features"
    assert {m["kind"] for m in manifest["materials"]} == set(synth.FEATURE_SHARES)
    assert cli.build_parser().parse_args(["synth", "x"]).mix == "default"
    assert all(cli.build_parser().parse_args(["synth", "x", "--mix", mix]).mix == mix for mix in synth.MIXES)


def test_synth_never_replaces_files_it_did_not_write(tmp_path, capsys):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "notes.txt").write_text("the user's")
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["synth", str(folder), "--n", "2", "--quiet"])
    assert exit_info.value.code == 2 and "--overwrite" in capsys.readouterr().err
    assert [p.name for p in folder.iterdir()] == ["notes.txt"] and (folder / "notes.txt").read_text() == "the user's"

    # An earlier bank is replaced whole, not mixed with the new one (its manifest would have been lost).
    bank = tmp_path / "bank"
    assert cli.main(["synth", str(bank), "--n", "2", "--quiet"]) == 0
    assert cli.main(["synth", str(bank), "--n", "2", "--mix", "features", "--quiet"]) == 0
    manifest = json.loads((bank / "bank.json").read_text())
    assert manifest["mix"] == "features"
    assert sorted(p.name for p in bank.iterdir() if p.name != MARKER) == sorted(
        ["bank.json", *(m["file"] for m in manifest["materials"])])
    assert not any(p.name.startswith(".") for p in tmp_path.iterdir())  # no staging folder left behind

    (bank / "notes.txt").write_text("added by the user")  # no longer only the bank's files
    with pytest.raises(SystemExit):
        cli.main(["synth", str(bank), "--n", "2", "--quiet"])
    assert (bank / "notes.txt").exists() and json.loads((bank / "bank.json").read_text())["mix"] == "features"
    assert cli.main(["synth", str(bank), "--n", "2", "--quiet", "--overwrite"]) == 0
    assert (bank / "notes.txt").read_text() == "added by the user"  # --overwrite writes beside it, never over it


def test_synth_command_rejects_bad_n(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["synth", str(tmp_path / "bank"), "--n", "0", "--quiet"])
    assert exit_info.value.code == 2 and "synth: error" in capsys.readouterr().err


def test_import_nbrdf_command(tmp_path, capsys):
    weights = SHARED_DATA / "merl-nbrdf" / "gold-paint.h5"
    if not weights.exists():
        pytest.skip(f"published NBRDF weights not found at {weights} (../shared is absent)")
    assert cli.main(["import-nbrdf", str(weights), str(tmp_path / "out"), "--quiet"]) == 0
    table = frenbrdf.read_merl(tmp_path / "out" / "gold-paint.binary")
    assert np.array_equal(frenbrdf.valid_mask(table), frenbrdf.merl_above_horizon())
    with pytest.raises(SystemExit):
        cli.main(["import-nbrdf", str(tmp_path / "absent.h5"), str(tmp_path / "out2"), "--quiet"])
    assert "absent.h5" in capsys.readouterr().err


def test_fit_nbrdf_reproduces_a_material(tmp_path):
    table = toy_table(np.random.default_rng(3))
    nbrdf = fit_nbrdf(table, FitConfig(epochs=1), progress=False)
    fitted = nbrdf.merl_table()
    valid = frenbrdf.valid_mask(table)
    def median_relative_error(prediction):
        return np.median(np.abs(prediction - table[:, valid]) / (table[:, valid] + 1e-2))

    constant = np.median(table[:, valid], axis=1, keepdims=True)  # the best a featureless fit can do
    assert median_relative_error(fitted[:, valid]) < 0.2 * median_relative_error(constant)
    assert np.array_equal(frenbrdf.valid_mask(fitted), valid)


def test_fit_nbrdf_on_samples_is_the_fit_of_a_table_holding_them():
    """fit_nbrdf_samples takes scattered samples (a measurement in both orders, which no table holds); on a table's
    own bins, in the table's order, it takes the same steps as fit_nbrdf on a table holding only those bins."""
    from frenbrdf.data.fitting import fit_nbrdf_samples
    from frenbrdf.io.sampling import bin_directions, sample_bins

    table = toy_table(np.random.default_rng(3))
    bins = np.sort(sample_bins(table, np.random.default_rng(4), 1500))
    sparse = np.full_like(table, -1.0)
    sparse.reshape(3, -1)[:, bins] = table.reshape(3, -1)[:, bins]
    config = FitConfig(epochs=2, hidden=(8, 8))
    from_table = fit_nbrdf(sparse, config, progress=False)
    from_samples = fit_nbrdf_samples(table.reshape(3, -1)[:, bins].T, bin_directions(bins), config, progress=False)
    for a, b in zip(from_table.params, from_samples.params, strict=True):
        np.testing.assert_allclose(a.numpy(), b.numpy(), rtol=1e-4, atol=1e-6)
    with pytest.raises(ValueError, match="finite"):
        fit_nbrdf_samples(np.full((10, 3), np.nan), bin_directions(bins[:10]), config, progress=False)


def test_fit_nbrdf_command_saves_a_loadable_nbrdf(tmp_path, capsys):
    path = tmp_path / "toy.binary"
    frenbrdf.write_merl(path, toy_table(np.random.default_rng(4)))
    assert cli.main(["fit-nbrdf", str(path), "--out", str(tmp_path / "fits"), "--epochs", "1", "--hidden", "8,8",
                     "--merl", "--quiet"]) == 0
    nbrdf = frenbrdf.NBRDF.from_weights(read_material(tmp_path / "fits" / "toy.pt"))
    assert [tuple(p.shape[1:]) for p in nbrdf.params][:2] == [(8, 6), (8,)]
    written = frenbrdf.read_merl(tmp_path / "fits" / "toy.binary")
    np.testing.assert_allclose(written, nbrdf.merl_table(), rtol=1e-12)
    with pytest.raises(ValueError, match="not a (readable )?saved NBRDF"):
        (tmp_path / "bad.pt").write_bytes(b"junk")
        read_material(tmp_path / "bad.pt")


def test_fit_nbrdf_replaces_a_fit_only_when_asked_and_checks_before_any_work(tmp_path, capsys):
    path, fits = tmp_path / "toy.binary", tmp_path / "fits"
    frenbrdf.write_merl(path, toy_table(np.random.default_rng(4)))
    command = ["fit-nbrdf", str(path), "--out", str(fits), "--epochs", "1", "--hidden", "8,8", "--quiet"]
    assert cli.main(command) == 0
    before = (fits / "toy.pt").read_bytes()
    for argv, message in ((command, "already holds toy.pt; pass --overwrite"),
                          ([*command[:-1], "--hidden", "abc"], "--hidden takes hidden widths"),
                          (["fit-nbrdf", str(tmp_path / "missing.binary"), "--out", str(tmp_path / "new")],
                           "missing.binary")):
        with pytest.raises(SystemExit):
            cli.main(argv)
        assert message in capsys.readouterr().err
    assert (fits / "toy.pt").read_bytes() == before and not (tmp_path / "new").exists()  # nothing made or lost
    assert cli.main([*command, "--overwrite", "--seed", "1"]) == 0 and (fits / "toy.pt").read_bytes() != before
