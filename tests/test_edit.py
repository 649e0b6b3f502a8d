"""Edits that keep a measured material (frenbrdf.models.editing, ``Model.edit``, ``frenbrdf edit``): the ends are the
reconstructions themselves, the path between is smooth, the plain latent interpolation is unchanged (and is the edit
of reconstructions with no residual), and the command refuses bad input in one line."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf import cli
from frenbrdf.io import read_samples
from frenbrdf.io.outputs import MARKER
from frenbrdf.models import NBRDF, EditedMaterial, interpolate
from frenbrdf.models.reconstruct import BUDGETS, RefineConfig
from frenbrdf.render import Scene, render

from .conftest import unit_vectors

#: A refinement that runs in a second or two and still moves the weights well beyond the decoding.
QUICK = RefineConfig(latent_steps=20, latent_lr=3e-2, weight_steps=80, weight_lr=3e-3, width=40)
#: How far an end may be from its reconstruction: |edit − f| / (f + ε), ε the mapping's offset (a relative error
#: that stays meaningful where f is 0).
END_TOLERANCE = 1e-6


@pytest.fixture(scope="module")
def model():
    return frenbrdf.Model.pretrained()


@pytest.fixture(scope="module")
def samples(toy_materials):
    files = sorted(toy_materials.glob("*.binary"))
    return [read_samples(files[i], samples=600, seed=i) for i in (0, 5)]


@pytest.fixture(scope="module")
def full(model, samples):
    """Two refined reconstructions: a reciprocal one, and an ordered one (its samples hold both orders)."""
    a = model.reconstruct(samples[0].values, (samples[0].wi, samples[0].wo), refine=QUICK)
    b_samples = samples[1]
    both = (np.concatenate([b_samples.wi, b_samples.wo]), np.concatenate([b_samples.wo, b_samples.wi]))
    b = model.reconstruct(np.concatenate([b_samples.values, b_samples.values * 1.05]), both, refine=QUICK)
    assert not a.nbrdf.ordered and b.nbrdf.ordered
    return a, b


@pytest.fixture(scope="module")
def pairs():
    rng = np.random.default_rng(3)
    wi, wo = unit_vectors(rng, 20000), unit_vectors(rng, 20000)
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    return wi, wo


def _relative(x: np.ndarray, y: np.ndarray, epsilon: float) -> float:
    return float(np.max(np.abs(x - y) / (np.abs(y) + epsilon)))


def test_the_ends_are_the_reconstructions(model, full, pairs):
    a, b = full
    edit = model.edit(a, b, [0.0, 1.0])
    epsilon = model.mapping.epsilon
    for k, result in enumerate(full):
        assert _relative(edit[k](*pairs), result.nbrdf(*pairs), epsilon) <= END_TOLERANCE
    table, truth = edit[1].merl_table(), b.nbrdf.merl_table()  # the ordered one: its table keeps the table's order
    above = truth >= 0
    assert np.array_equal(table < 0, truth < 0)  # the same missing bins
    assert _relative(table[above], truth[above], epsilon) <= END_TOLERANCE
    # The latent interpolation's ends are the decodings, which the refinement left behind.
    decoded = model.decode(a.z)(*pairs)
    assert _relative(decoded, a.nbrdf(*pairs), epsilon) > 100 * END_TOLERANCE


def test_between_the_ends_it_is_the_latent_path_plus_the_faded_residuals(model, full, pairs):
    a, b = full
    t = 0.3
    mapping = model.mapping

    def y(brdf):
        return mapping.forward(brdf(*pairs), mapping.reference_at(*pairs))

    expected = (y(model.decode(interpolate(a.z, b.z, t))) + (1 - t) * (y(a.nbrdf) - y(model.decode(a.z)))
                + t * (y(b.nbrdf) - y(model.decode(b.z))))
    edited = model.edit(a, b, t)
    assert len(edited) == 1 and edited.t.tolist() == [t]
    np.testing.assert_allclose(edited(*pairs), mapping.inverse(expected, mapping.reference_at(*pairs)), rtol=1e-9,
                               atol=1e-12)


def test_the_edit_moves_smoothly_along_t(model, full):
    """Eleven steps: no step of the renders nor of the decoded weights is more than a few times the median step."""
    a, b = full
    ts = np.linspace(0, 1, 11)
    edited = model.edit(a, b, ts)
    scene = Scene(resolution=48)
    renders = np.stack([render(edited[k], scene) for k in range(len(ts))])
    weights = np.stack([torch.cat([p.reshape(-1) for p in path.params]).numpy() for path in edited.paths])
    for what, frames in (("renders", renders), ("decoded weights", weights)):
        steps = np.sqrt(np.mean(np.diff(frames, axis=0).reshape(len(ts) - 1, -1) ** 2, axis=1))
        assert np.median(steps) > 0, what
        assert steps.max() <= 3 * np.median(steps), f"{what}: a jump, steps {steps}"


def test_the_plain_latent_interpolation_is_unchanged_and_is_the_edit_without_residuals(model, samples):
    z_a, z_b = np.arange(4.0), np.ones(4)
    np.testing.assert_array_equal(interpolate(z_a, z_b, [0, 0.25, 1]), [z_a, 0.75 * z_a + 0.25, z_b])
    assert frenbrdf.interpolate is interpolate
    # Reconstructions that stay in the latent space carry no residual: the edit is the latent interpolation.
    latent = [model.reconstruct(s.values, (s.wi, s.wo), refine=RefineConfig(latent_steps=20)) for s in samples]
    ts = [0.0, 0.4, 1.0]
    decoded = model.decode(interpolate(latent[0].z, latent[1].z, ts))
    edited = model.edit(*latent, ts)
    rng = np.random.default_rng(5)
    wi, wo = unit_vectors(rng, 2000), unit_vectors(rng, 2000)
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    for k in range(len(ts)):
        np.testing.assert_allclose(edited[k](wi, wo), decoded[k](wi, wo), rtol=1e-4, atol=1e-7)


def test_the_edit_is_the_viewers_kept_mode(model, full, pairs):
    from frenbrdf.render.viewer.sources import Material, combined, make_edit

    a, b = full
    page_edit = make_edit(Material(a.nbrdf, "a", "test", a.z), Material(b.nbrdf, "b", "test", b.z), model=model)
    assert page_edit.modes == ("kept", "latent")
    page = combined(page_edit.terms(0.5, "kept"), page_edit.mapping)(*pairs)
    np.testing.assert_allclose(model.edit(a, b, 0.5)(*pairs), page, rtol=1e-4, atol=1e-7)


def test_bad_positions_and_foreign_reconstructions_are_refused(model, full):
    a, b = full
    for t, message in [(1.5, r"t must lie in \[0, 1\]"), (-0.1, r"t must lie in \[0, 1\]"),
                       (float("nan"), "t must be finite"), ([[0.5]], "a number or a 1-D array")]:
        with pytest.raises(ValueError, match=message):
            model.edit(a, b, t)
    with pytest.raises(ValueError, match=r"latent has shape \(3,\)"):
        model.edit(a, type(a)(np.zeros(3), b.nbrdf), 0.5)
    other = frenbrdf.models.mapping.LogRelativeMapping(model.mapping.reference * 2, model.mapping.epsilon)
    with pytest.raises(ValueError, match="maps reflectance unlike this model"):
        model.edit(a, type(a)(b.z, NBRDF(b.nbrdf.params, other)), 0.5)
    several = model.edit(a, b, [0.2, 0.8])
    assert isinstance(several, EditedMaterial) and len(several) == 2
    with pytest.raises(ValueError, match="holds 2 materials"):
        several.merl_table()


# --------------------------------------------------------------------------- the command


@pytest.fixture()
def quick_budgets(monkeypatch):
    """The command's named budgets, cut to a second's work (the command reads them by name)."""
    monkeypatch.setitem(BUDGETS, "full", QUICK)
    monkeypatch.setitem(BUDGETS, "latent", RefineConfig(latent_steps=20, latent_lr=3e-2, schedule="cosine"))


def _edit(*args):
    return cli.main(["edit", *map(str, args), "--quiet"])


def test_the_command_end_to_end(toy_materials, tmp_path, capsys, quick_budgets):
    files = sorted(toy_materials.glob("*.binary"))
    out = tmp_path / "edit"
    assert _edit(files[0], files[5], "--out", out, "--samples", 300, "--t", 0, 0.5, "--t", 1, "--resolution", 24,
                 "--json") == 0
    report = json.loads((out / "edit.json").read_text())
    assert json.loads(capsys.readouterr().out) == report
    names = [f"t-{t}" for t in ("0.000", "0.500", "1.000")]
    assert sorted(p.name for p in out.iterdir() if p.name != MARKER) == report["files"] == sorted(
        ["edit.json", "strip.png", *(n + s for n in names for s in (".binary", ".png"))])
    assert report["mode"] == "kept" and report["t"] == [0.0, 0.5, 1.0] and report["refine"]["budget"] == "full"
    assert set(report["ends"]) == {"a", "b"} and all(np.isfinite(m["psnr"]) for m in report["ends"].values())
    # t = 0 is the material `reconstruct` gives of the same file, with the same settings.
    assert cli.main(["reconstruct", str(files[0]), "--out", str(tmp_path / "a"), "--samples", "300", "--quiet"]) == 0
    table, truth = frenbrdf.read_merl(out / "t-0.000.binary"), frenbrdf.read_merl(tmp_path / "a" / "material.binary")
    assert _relative(table, truth, 2e-3) <= END_TOLERANCE
    import matplotlib.image

    strip = matplotlib.image.imread(out / "strip.png")
    # truth a | gap | three positions | gap | truth b; 24 pixels are too narrow for titles (tests/test_titled_row.py)
    assert strip.shape[:2] == (24, 5 * 24 + 2 * 1)


def test_the_command_gives_the_plain_latent_interpolation_on_request(toy_materials, tmp_path, capsys, quick_budgets):
    """Its ends are the decodings of the latents (refined with the latent budget)."""
    files = sorted(toy_materials.glob("*.binary"))
    assert _edit(files[0], files[5], "--out", tmp_path / "latent", "--samples", 300, "--t", 0, "--latent",
                 "--resolution", 16) == 0
    report = json.loads((tmp_path / "latent" / "edit.json").read_text())
    assert report["mode"] == "latent" and report["refine"]["budget"] == "latent"
    decoded = frenbrdf.Model.pretrained().decode(report["reconstructions"]["a"]["z"]).merl_table()
    assert _relative(frenbrdf.read_merl(tmp_path / "latent" / "t-0.000.binary"), decoded, 2e-3) <= 1e-5
    assert "latent interpolation between" in capsys.readouterr().out


def test_the_same_file_twice_is_an_edit_that_stays(toy_materials, tmp_path, capsys, quick_budgets):
    source = sorted(toy_materials.glob("*.binary"))[2]
    assert _edit(source, source, "--out", tmp_path / "same", "--samples", 300, "--t", 0.5, "--resolution", 16) == 0
    assert "edit keeping each material between" in capsys.readouterr().out
    assert cli.main(["reconstruct", str(source), "--out", str(tmp_path / "a"), "--samples", "300", "--quiet"]) == 0
    halfway = frenbrdf.read_merl(tmp_path / "same" / "t-0.500.binary")
    assert _relative(halfway, frenbrdf.read_merl(tmp_path / "a" / "material.binary"), 2e-3) <= END_TOLERANCE


@pytest.mark.parametrize(("args", "message"), [
    (["--t", "1.5"], "argument --t: expected a number in 0 … 1, got '1.5'"),
    (["--t", "nan"], "argument --t: expected a number in 0 … 1, got 'nan'"),
    (["--t", "-0.5"], "argument --t: expected a number in 0 … 1, got '-0.5'"),
    (["--t", "0.5", "--t", "0.5"], "positions given twice, or closer than 0.001 (both would write t-0.500.*)"),
    (["--out-is-input"], "is the input"),
    (["--t", *(str(k / 40) for k in range(34))], "give 1 to 33 positions t"),
    (["--resolution", "2048"], "argument --resolution: expected a whole number in 8 … 1,024"),
    (["--samples", "10"], "argument --samples: expected a number ≥"),
])
def test_bad_input_is_refused_in_one_line(toy_materials, tmp_path, capsys, args, message):
    source = sorted(toy_materials.glob("*.binary"))[0]
    out = source.parent if args == ["--out-is-input"] else tmp_path / "out"
    args = [] if args == ["--out-is-input"] else args
    with pytest.raises(SystemExit) as exit_info:
        _edit(source, source, "--out", out, *args)
    last = capsys.readouterr().err.strip().splitlines()[-1]  # argparse's usage lines come first
    assert exit_info.value.code == 2 and last.startswith("frenbrdf edit: error:") and message in last, last
    assert not (tmp_path / "out").exists()
