"""Test-time refinement, `frenbrdf reconstruct`, and the packaged (pretrained) model."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf import cli
from frenbrdf.io import read_material, read_samples, write_material
from frenbrdf.io.outputs import MARKER
from frenbrdf.models import pretrained
from frenbrdf.models.reconstruct import BUDGETS, RefineConfig, reconstruct, refine_config

from .conftest import script_module, tiny
from .io.test_bsdf_native import flat_material, tensor_file


@pytest.fixture(scope="module")
def run_dir(toy_materials, tmp_path_factory):
    from frenbrdf.training import train

    return train(tiny("frenbrdf", toy_materials, tmp_path_factory.mktemp("reconstruct") / "run", epochs=2)).path


@pytest.fixture(scope="module")
def model(run_dir):
    return frenbrdf.Model.load(run_dir)


@pytest.fixture(scope="module")
def material(toy_materials):
    return read_samples(sorted(toy_materials.glob("*.binary"))[0], samples=2000, seed=1)


def _params(result):
    return torch.cat([p.reshape(-1) for p in result.nbrdf.params])


def test_refinement_lowers_the_sample_loss(model, material):
    result = reconstruct(model, material.values, (material.wi, material.wo),
                         refine=RefineConfig(latent_steps=40, weight_steps=60, latent_lr=0.05, weight_lr=3e-3))
    assert set(result.timings) == set(result.losses) == {"encode", "latent", "weights"}
    assert result.losses["latent"] < result.losses["encode"]
    assert result.losses["weights"] < result.losses["latent"]
    assert result.steps == {"latent": 40, "weights": 60}
    assert np.all(np.isfinite(result.nbrdf(material.wi, material.wo)))


def test_cosine_schedule_starts_at_the_rate_then_decays(model, material):
    def z_after(steps, schedule):
        config = RefineConfig(latent_steps=steps, latent_lr=0.05, schedule=schedule)
        return reconstruct(model, material.values, (material.wi, material.wo), refine=config)

    np.testing.assert_array_equal(z_after(1, "cosine").z, z_after(1, "constant").z)  # the first step: the same rate
    cosine, constant = z_after(20, "cosine"), z_after(20, "constant")
    assert not np.allclose(cosine.z, constant.z)
    assert cosine.losses["latent"] < cosine.losses["encode"]
    with pytest.raises(ValueError, match="schedule must be one of"):
        RefineConfig(schedule="linear")


def test_no_refinement_is_the_encoder(model, material):
    result = model.reconstruct(material.values, (material.wi, material.wo), refine="none")
    z = model.encode(material.values, (material.wi, material.wo))
    np.testing.assert_allclose(result.z, z, rtol=1e-6, atol=1e-7)
    np.testing.assert_array_equal(_params(result), torch.cat([p.reshape(-1) for p in model.decode(z).params]))
    assert set(result.losses) == {"encode"}


def test_refinement_is_deterministic_from_the_seed(model, material):
    config = RefineConfig(latent_steps=5, weight_steps=5, batch=256, seed=3)  # mini-batches: the seed matters
    run = [model.reconstruct(material.values, (material.wi, material.wo), refine=config) for _ in range(2)]
    np.testing.assert_array_equal(run[0].z, run[1].z)
    assert torch.equal(_params(run[0]), _params(run[1]))
    other = model.reconstruct(material.values, (material.wi, material.wo),
                              refine=RefineConfig(latent_steps=5, weight_steps=5, batch=256, seed=4))
    assert not torch.equal(_params(run[0]), _params(other))


@pytest.mark.parametrize("stage, steps", [("latent", "latent_steps"), ("weights", "weight_steps")])
def test_the_time_budget_stops_a_stage(model, material, stage, steps):
    result = reconstruct(model, material.values, (material.wi, material.wo),
                         refine=RefineConfig(**{steps: 10**6}, seconds=0.2))
    assert 0 < result.steps[stage] < 10**6 and result.timings[stage] < 5


def test_inputs_are_checked_like_encode(model, material):
    with pytest.raises(ValueError, match="values must have shape"):
        model.reconstruct(material.values[:, :2], (material.wi, material.wo))
    bad = material.values.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="finite and ≥ 0"):
        model.reconstruct(bad, (material.wi, material.wo))
    with pytest.raises(ValueError, match="refine must be one of"):
        model.reconstruct(material.values, (material.wi, material.wo), refine="most")
    with pytest.raises(ValueError, match="latent_steps must be ≥ 0"):
        RefineConfig(latent_steps=-1)


@pytest.mark.parametrize("hidden", [(32, 32), (5, 7, 4), (1, 1)])
def test_widening_keeps_what_the_nbrdf_gives_back(hidden):
    from frenbrdf.models.nbrdf import NBRDFConfig, nbrdf_forward, widen_params

    generator = torch.Generator().manual_seed(0)
    params = [torch.randn(2, *shape, generator=generator) for shape in NBRDFConfig(hidden).shapes()]
    wide = widen_params(params, 48, generator)
    assert [tuple(p.shape) for p in wide] == [(2, *shape) for shape in NBRDFConfig((48,) * len(hidden)).shapes()]
    assert all(float(p.abs().sum()) > 0 for p in wide[0::2][:-1])  # new incoming weights are drawn, not 0
    coords = torch.randn(2, 300, 6, generator=generator)
    torch.testing.assert_close(nbrdf_forward(wide, coords), nbrdf_forward(params, coords), rtol=1e-5, atol=1e-5)
    narrow = widen_params(params, 1, generator)  # layers already as wide are kept as they are
    assert all(torch.equal(a, b) for a, b in zip(narrow, params, strict=True))


def test_a_wider_full_refinement_fits_further(model, material):
    directions = (material.wi, material.wo)
    base = dict(latent_steps=5, weight_steps=60, weight_lr=3e-3)
    plain = model.reconstruct(material.values, directions, refine=RefineConfig(**base))
    wide = model.reconstruct(material.values, directions, refine=RefineConfig(**base, width=48))
    again = model.reconstruct(material.values, directions, refine=RefineConfig(**base, width=48))
    assert wide.nbrdf.params[0].shape[1] == 48 and plain.nbrdf.params[0].shape[1] != 48
    assert wide.losses["latent"] == plain.losses["latent"]  # widening starts where the latent stage ended
    assert wide.losses["weights"] < wide.losses["latent"]
    torch.testing.assert_close(_params(wide), _params(again))  # the new weights are drawn from the seed
    assert np.isfinite(wide.nbrdf(*directions)).all()


@pytest.mark.parametrize("starts", [0, -1, 1.5, 65, True])
def test_starts_must_be_a_count_of_latents(starts):
    with pytest.raises(ValueError, match="starts must be an integer from 1 to 64"):
        RefineConfig(latent_steps=10, starts=starts)


def test_several_starts_with_one_encoder_refine_once(model, material):
    config = RefineConfig(latent_steps=5, latent_lr=0.05)
    once, asked = (reconstruct(model, material.values, (material.wi, material.wo), refine=dataclasses.replace(config,
                   starts=n)) for n in (1, 4))
    assert asked.steps == once.steps == {"latent": 5}
    np.testing.assert_array_equal(asked.z, once.z)


def test_a_width_needs_the_weight_stage_and_a_sane_size(model, material):
    with pytest.raises(ValueError, match="width must be None or 1 to 1024 with weight_steps > 0"):
        RefineConfig(latent_steps=10, width=64)
    for bad in (100000, 0, 48.5, float("nan"), "48"):
        with pytest.raises(ValueError, match="width must be"):
            RefineConfig(weight_steps=10, width=bad)
    kept = model.reconstruct(material.values, (material.wi, material.wo), refine=RefineConfig(weight_steps=2, width=1))
    assert kept.nbrdf.params[0].shape[1] == model.decode(kept.z).params[0].shape[1]  # never narrowed


def test_full_refines_64_wide_by_default(model, material, tmp_path):
    assert refine_config("full").width == 64 and refine_config("latent").width is None
    result = model.reconstruct(material.values, (material.wi, material.wo),
                               refine=dataclasses.replace(refine_config("full"), weight_steps=3))
    assert all(p.shape[1] == 64 for p in result.nbrdf.params[:-2])


@pytest.mark.parametrize("kind", ["per_tensor", "all"])
def test_the_weight_decays_are_the_penalty_gradients(kind):
    from frenbrdf.models.losses import LossConfig, weight_penalty
    from frenbrdf.models.reconstruct import _weight_decays

    generator = torch.Generator().manual_seed(0)
    params = [torch.randn(1, *shape, generator=generator, requires_grad=True) for shape in [(32, 6), (32,), (3, 32), (3,)]]
    loss = LossConfig(lambda_weights=0.01, weight_penalty=kind)
    (loss.lambda_weights * weight_penalty(params, kind)).backward()
    for param, decay in zip(params, _weight_decays(params, loss), strict=True):
        torch.testing.assert_close(param.grad, decay * param.detach())


def test_the_weight_stage_steps_as_with_its_penalty_differentiated(model, material, monkeypatch):
    from frenbrdf.models.losses import reconstruction_loss, weight_penalty
    from frenbrdf.models.nbrdf import mapped_samples, nbrdf_forward

    monkeypatch.setitem(model.loss, "lambda_weights", 10.0)  # the penalty dominates: its steps show
    directions = (material.wi, material.wo)
    result = reconstruct(model, material.values, directions, refine=RefineConfig(weight_steps=5, weight_lr=1e-2))
    mapped, coords, cos_in = (torch.from_numpy(np.asarray(a, dtype=np.float32))[None]
                              for a in mapped_samples(model.mapping, material.values, directions))
    z = torch.from_numpy(model.encode(material.values, directions).astype(np.float32))[None]
    with torch.no_grad():
        params = [p.clone().requires_grad_(True) for p in model.network.decoder(z)]
    optimizer = torch.optim.Adam(params, lr=1e-2)
    for _ in range(5):  # 2000 samples: every step sees all of them, as the stage's do
        objective = reconstruction_loss(nbrdf_forward(params, coords), mapped, cos_in, model.loss["kind"]) \
            + 10.0 * weight_penalty(params, model.loss["weight_penalty"])
        optimizer.zero_grad()
        objective.backward()
        optimizer.step()
    torch.testing.assert_close(_params(result), torch.cat([p.detach().reshape(-1) for p in params]),
                               rtol=1e-4, atol=1e-5)


@pytest.mark.parametrize("kind, hidden", [("l1", (20, 20)), ("mse", (20, 20)), ("l1", (7, 9, 5))])
def test_the_native_weight_steps_are_torch_adams_on_the_given_batches(kind, hidden):
    from frenbrdf import _native
    from frenbrdf.models.losses import reconstruction_loss
    from frenbrdf.models.nbrdf import NBRDFConfig, nbrdf_forward

    generator = torch.Generator().manual_seed(0)
    shapes = NBRDFConfig(hidden).shapes()  # widths no vector length divides; two and three hidden layers
    params = [0.5 * torch.randn(1, *shape, generator=generator) for shape in shapes]
    coords, values = torch.randn(1, 300, 6, generator=generator), torch.randn(1, 300, 3, generator=generator)
    cos_in = torch.rand(1, 300, generator=generator)
    rows = torch.randint(300, (8, 100), generator=generator)  # a whole block of samples and a part of one
    rates, decays = np.linspace(1e-2, 1e-3, 8), [1e-3, 0.0] * (len(shapes) // 2)
    fit = _native.WeightFit([p[0].numpy() for p in params], decays, coords[0].numpy(), values[0].numpy(),
                            cos_in[0].numpy(), kind)
    losses = fit.run(rates.astype(np.float32), rows.numpy())

    reference = [p.clone().requires_grad_(True) for p in params]
    optimizer = torch.optim.Adam([{"params": [p], "weight_decay": d} for p, d in zip(reference, decays, strict=True)])
    for batch, rate, loss in zip(rows, rates, losses, strict=True):
        value = reconstruction_loss(nbrdf_forward(reference, coords[:, batch]), values[:, batch], cos_in[:, batch], kind)
        assert loss == pytest.approx(float(value.detach()), rel=1e-5)
        for group in optimizer.param_groups:
            group["lr"] = float(np.float32(rate))
        optimizer.zero_grad()
        value.backward()
        optimizer.step()
    for got, want in zip(fit.tensors(), reference, strict=True):
        np.testing.assert_allclose(got, want.detach().reshape(-1).numpy(), rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("hidden", [(16,), (16, 12), (8, 8, 8)])
def test_the_frozen_decoder_decodes_and_pulls_back_as_autograd(hidden):
    from frenbrdf.models.hypernetwork import DecoderConfig, FrozenDecoder, HyperNetwork
    from frenbrdf.models.nbrdf import NBRDFConfig

    torch.manual_seed(0)
    decoder = HyperNetwork(5, NBRDFConfig((7, 9)).shapes(), DecoderConfig(hidden))
    frozen = FrozenDecoder(decoder)
    z = torch.randn(1, 5, requires_grad=True)
    flat = torch.cat([p.reshape(-1) for p in decoder(z)])
    torch.testing.assert_close(frozen.weights(z.detach()), flat.detach())
    gradient = torch.randn(flat.shape)
    flat.backward(gradient)
    torch.testing.assert_close(frozen.pullback(gradient), z.grad, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("anchor", [0.0, 0.5])
def test_the_latent_steps_are_torch_adams_through_the_decoder(model, material, anchor):
    """Stage 1 takes the decoded NBRDF's gradient from the native core: the same steps as differentiating the
    whole objective in torch, on the same batches (and the anchor's second loss, where there is one)."""
    from frenbrdf.models import reconstruct as stage
    from frenbrdf.models.losses import reconstruction_loss
    from frenbrdf.models.nbrdf import mapped_samples, nbrdf_forward

    config = RefineConfig(latent_steps=15, latent_lr=0.05, batch=700, anchor=anchor, schedule="cosine")
    result = reconstruct(model, material.values, (material.wi, material.wo), refine=config)

    mapped, coords, cos_in = (torch.from_numpy(np.asarray(a, dtype=np.float32))[None]
                              for a in mapped_samples(model.mapping, material.values, (material.wi, material.wo)))
    kind, decoder = model.loss["kind"], model.network.decoder
    start = model.encoding(material.values, (material.wi, material.wo)).z
    z = torch.from_numpy(start.astype(np.float32))[None]
    anchors = stage._anchor_samples(material.wi, material.wo) if anchor else None
    if anchors is not None:
        with torch.no_grad():
            held = nbrdf_forward(decoder(z), anchors.coords)
    z.requires_grad_(True)
    optimizer = torch.optim.Adam([z], weight_decay=2 * stage._loss_config(model).lambda_latent / z.numel())
    generator = torch.Generator().manual_seed(config.seed + stage.STAGES.index("latent"))
    decoder.requires_grad_(False)
    try:
        for rate in stage._learning_rates(config.latent_lr, config.latent_steps, config.schedule):
            rows = torch.randint(coords.shape[1], (config.batch,), generator=generator)
            params = decoder(z)
            value = reconstruction_loss(nbrdf_forward(params, coords[:, rows]), mapped[:, rows], cos_in[:, rows], kind)
            if anchors is not None:
                value = value + anchor * reconstruction_loss(nbrdf_forward(params, anchors.coords), held,
                                                             anchors.cos_in, kind)
            optimizer.param_groups[0]["lr"] = float(rate)
            optimizer.zero_grad()
            value.backward()
            optimizer.step()
    finally:
        decoder.requires_grad_(True)
    assert not np.allclose(result.z, start, atol=1e-3)  # z moved: the test compares steps
    np.testing.assert_allclose(result.z, z.detach()[0].numpy(), rtol=1e-4, atol=1e-5)


@pytest.mark.parametrize("change, message", [
    ({"coords": np.zeros((4, 5), np.float32)}, "coords must have shape (N, 6)"),
    ({"values": np.full((4, 3), np.nan, np.float32)}, "values hold NaN or inf"),
    ({"tensors": [np.zeros((6, 3), np.float32), np.zeros(6, np.float32)]}, "do not chain from 6 inputs"),
    ({"decays": [0.0]}, "weight decays"),
    ({"loss": "l3"}, "loss must be 'l1' or 'mse'"),
])
def test_the_native_weight_fit_names_what_does_not_fit(change, message):
    from frenbrdf import _native

    arguments = {"tensors": [np.zeros((3, 6), np.float32), np.zeros(3, np.float32)], "decays": [0.0, 0.0],
                 "coords": np.zeros((4, 6), np.float32), "values": np.zeros((4, 3), np.float32),
                 "cos_in": np.ones(4, np.float32), "loss": "l1"}
    fit = _native.WeightFit(*arguments.values())
    with pytest.raises(ValueError, match=re.escape(message)):
        _native.WeightFit(*(arguments | change).values())
    for rates, rows, error in [([0.0], None, "positive"), ([1e-3], [[4]], "out of range"),
                               ([1e-3], [[-1]], "rows must lie")]:
        with pytest.raises(ValueError, match=error):
            fit.run(np.array(rates, np.float32), None if rows is None else np.array(rows, np.int64))


def test_named_budgets_are_copies():
    config = refine_config("full")
    config.latent_steps = 1
    assert BUDGETS["full"].latent_steps != 1 and refine_config("none").weight_steps == 0


# --------------------------------------------------------------------------- the command


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_the_latent_stages_adam_takes_torchs_adam_steps_to_the_bit(dtype):
    """``Adam`` (the latent stage's, to spare torch.optim's import of torch._dynamo) against torch's own
    single-tensor Adam: two tensors with their own weight decay (one none), a falling rate, both precisions.
    ``Adam`` takes the bias correction's root as torch does (``** 0.5``); ``math.sqrt`` differs from it in the last
    bit at five step counts below 20,000 (the first 1270), a difference too small to reach the weights here."""
    from frenbrdf.models.adam import Adam

    generator = torch.Generator().manual_seed(0)
    ours = [torch.randn(64, generator=generator, dtype=dtype), torch.randn(3, 5, generator=generator, dtype=dtype)]
    theirs = [p.clone() for p in ours]
    decays = [0.003, 0.0]
    adam = Adam(ours, decays)
    reference = torch.optim.Adam([{"params": [p], "weight_decay": d} for p, d in zip(theirs, decays, strict=True)],
                                 lr=1.0, foreach=False, fused=False)
    for step in range(1500):
        rate = 0.03 * (1 + np.cos(np.pi * step / 1500)) / 2
        for mine, other in zip(ours, theirs, strict=True):
            mine.grad = torch.randn(mine.shape, generator=generator, dtype=dtype)
            other.grad = mine.grad.clone()
        for group in reference.param_groups:
            group["lr"] = rate
        adam.step(rate)
        reference.step()
    for mine, other in zip(ours, theirs, strict=True):
        assert torch.equal(mine, other)


def _reconstruct(*args):
    return cli.main(["reconstruct", *map(str, args), "--quiet"])


def test_the_command_end_to_end(run_dir, toy_materials, tmp_path, capsys):
    source = sorted(toy_materials.glob("*.binary"))[1]
    out = tmp_path / "result"
    assert _reconstruct(source, "--out", out, "--model", run_dir, "--samples", 500, "--refine", "full",
                        "--json") == 0
    printed = json.loads(capsys.readouterr().out)
    report = json.loads((out / "reconstruction.json").read_text())
    assert printed == report
    assert sorted(p.name for p in out.iterdir() if p.name != MARKER) == report["files"] == sorted(
        ["comparison.png", "material.binary", "material.pt", "reconstruction.json", "render.png", "spectrum.png",
         "truth.png"])
    assert set(report["spectrum"]["relative_error_by_band"]["reconstruction"]) == {"l 0", "l 1–4", "l 5–16", "l 17–49"}
    assert {"rmse", "psnr", "ssim", "delta_e", "lfre"} <= set(report["metrics"])
    assert report["input"] == {"path": str(source), "kind": "merl", "samples": 500, "pattern": "merl-bins"}
    assert set(report["timings_s"]) == {"encode", "latent", "weights"} and len(report["z"]) == 8
    assert report["encoder"] == {"encoders": 1, "choice": "mean"}  # a run's one encoder: z is its latent
    # What was written is what the renderers and the MERL reader take.
    assert frenbrdf.read_merl(out / "material.binary").shape == (3, 90, 90, 180)
    assert cli.main(["render", str(out / "material.pt"), "--out", str(tmp_path / "x.png"), "--resolution", "32"]) == 0
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging folder left


def test_the_command_samples_a_material_by_the_pattern_asked_for(run_dir, toy_materials, tmp_path, capsys):
    source = sorted(toy_materials.glob("*.binary"))[3]
    assert _reconstruct(source, "--out", tmp_path / "gonio", "--model", run_dir, "--samples", 300,
                        "--pattern", "gonioreflectometer", "--refine", "none") == 0
    report = json.loads((tmp_path / "gonio" / "reconstruction.json").read_text())
    assert report["input"] == {"path": str(source), "kind": "merl", "samples": 300, "pattern": "gonioreflectometer"}
    assert np.isfinite(report["metrics"]["psnr"])
    material = read_samples(source, samples=300, pattern="gonioreflectometer")  # what the model was given
    z = frenbrdf.Model.load(run_dir).encode(material.values, (material.wi, material.wo))
    np.testing.assert_allclose(report["z"], z.tolist(), rtol=1e-5, atol=1e-6)
    with pytest.raises(SystemExit) as exit_info:
        _reconstruct(source, "--out", tmp_path / "x", "--model", run_dir, "--pattern", "goniometer")
    assert exit_info.value.code == 2 and "expected a sampling pattern, one of merl-bins, " in capsys.readouterr().err
    csv = tmp_path / "measured.csv"
    from frenbrdf.io import write_samples

    write_samples(csv, material)
    with pytest.raises(SystemExit) as exit_info:
        _reconstruct(csv, "--out", tmp_path / "csv", "--model", run_dir, "--pattern", "uniform")
    assert exit_info.value.code == 2 and "--pattern picks samples from a MERL file or a .bsdf" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        _reconstruct(source, "--out", tmp_path / "all", "--model", run_dir, "--pattern", "uniform", "--samples", "all")
    assert "--samples all draws every MERL bin; --pattern uniform draws N pairs" in capsys.readouterr().err
    assert not (tmp_path / "x").exists() and not (tmp_path / "csv").exists() and not (tmp_path / "all").exists()
    capsys.readouterr()
    assert _reconstruct(source, "--out", tmp_path / "mirror", "--model", run_dir, "--samples", 300,
                        "--pattern", "specular", "--refine", "none") == 0
    warnings = json.loads((tmp_path / "mirror" / "reconstruction.json").read_text())["coverage"]["warnings"]
    assert len(warnings) == 1 and f"warning: {warnings[0]}" in capsys.readouterr().err
    assert json.loads((tmp_path / "gonio" / "reconstruction.json").read_text())["coverage"]["warnings"] == []


def test_the_command_on_a_csv_and_all_bins(run_dir, toy_materials, tmp_path):
    material = read_samples(sorted(toy_materials.glob("*.binary"))[2], samples=300)
    rows = np.concatenate([material.wi, material.wo, material.values], axis=1)
    csv = tmp_path / "measured.csv"
    csv.write_text("wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b\n" + "\n".join(",".join(str(float(v)) for v in r) for r in rows))
    assert _reconstruct(csv, "--out", tmp_path / "csv", "--model", run_dir, "--refine", "none") == 0
    report = json.loads((tmp_path / "csv" / "reconstruction.json").read_text())
    assert report["input"]["kind"] == "csv" and "metrics" not in report
    assert not (tmp_path / "csv" / "truth.png").exists()

    source = sorted(toy_materials.glob("*.binary"))[2]
    assert _reconstruct(source, "--out", tmp_path / "all", "--model", run_dir, "--samples", "all",
                        "--refine", "none") == 0
    report = json.loads((tmp_path / "all" / "reconstruction.json").read_text())
    assert report["input"]["samples"] == int(frenbrdf.valid_mask(frenbrdf.read_merl(source)).sum())


def test_a_failing_input_leaves_no_output(run_dir, tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b\n0,0,1,0,0,1,1,1,x\n")
    with pytest.raises(SystemExit) as exit_info:
        _reconstruct(bad, "--out", tmp_path / "out", "--model", run_dir)
    assert exit_info.value.code == 2 and "bad.csv: row 2, column b" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_command_widens_on_request_and_names_a_width_without_full(run_dir, toy_materials, tmp_path, capsys):
    source = sorted(toy_materials.glob("*.binary"))[1]
    out = tmp_path / "wide"
    assert _reconstruct(source, "--out", out, "--model", run_dir, "--samples", 300, "--width", 40) == 0
    assert cli.main(["render", str(out / "material.pt"), "--out", str(tmp_path / "x.png"), "--resolution", "16"]) == 0
    assert read_material(out / "material.pt").params[0].shape[0] == 40  # saved 40 wide, and it renders
    assert _reconstruct(source, "--out", tmp_path / "default", "--model", run_dir, "--samples", 300) == 0
    assert read_material(tmp_path / "default" / "material.pt").params[0].shape[0] == 64  # full's default
    with pytest.raises(SystemExit) as exit_info:
        _reconstruct(source, "--out", tmp_path / "latent", "--model", run_dir, "--refine", "latent", "--width", 40)
    assert exit_info.value.code == 2 and "--width sets the NBRDF that --refine full fits" in capsys.readouterr().err
    assert not (tmp_path / "latent").exists()
    with pytest.raises(SystemExit):
        _reconstruct(source, "--out", tmp_path / "none", "--model", run_dir, "--refine", "none", "--reciprocal")
    assert "--reciprocal sets the NBRDF" in capsys.readouterr().err and not (tmp_path / "none").exists()


def test_the_command_weighs_coverage_on_request_and_refuses_it_without_a_latent_stage(run_dir, toy_materials,
                                                                                        tmp_path, capsys):
    source = sorted(toy_materials.glob("*.binary"))[1]
    common = ("--model", run_dir, "--refine", "latent", "--pattern", "uniform", "--samples", 300)
    assert _reconstruct(source, "--out", tmp_path / "plain", *common, "--coverage", 0) == 0
    assert _reconstruct(source, "--out", tmp_path / "weighted", *common, "--coverage", 16) == 0
    plain, weighted = (json.loads((tmp_path / name / "reconstruction.json").read_text())
                       for name in ("plain", "weighted"))
    assert not np.allclose(plain["z"], weighted["z"])
    assert (plain["refine"]["coverage_k"], weighted["refine"]["coverage_k"]) == (0, 16)
    with pytest.raises(SystemExit) as exit_info:
        _reconstruct(source, "--out", tmp_path / "none", "--model", run_dir, "--refine", "none", "--coverage", 8)
    assert exit_info.value.code == 2 and "--coverage weighs the samples" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        _reconstruct(source, "--out", tmp_path / "bad", "--model", run_dir, "--coverage", -2)
    assert "whole number in 0" in capsys.readouterr().err
    assert not (tmp_path / "none").exists() and not (tmp_path / "bad").exists()


def test_coverage_weights_are_on_by_default_where_the_samples_come_from_a_device(run_dir, toy_materials, tmp_path):
    from frenbrdf.io import write_samples
    from frenbrdf.material.outputs import DEVICE_COVERAGE_K

    source = sorted(toy_materials.glob("*.binary"))[1]
    quick = ("--model", run_dir, "--refine", "latent", "--samples", 300)
    write_samples(tmp_path / "device.astm", read_samples(source, samples=300, seed=2, pattern="gonioreflectometer"))
    write_samples(tmp_path / "scattered.csv", read_samples(source, samples=300, seed=2))
    cases = {"bins": (source,), "uniform": (source, "--pattern", "uniform"), "astm": (tmp_path / "device.astm",),
             "csv": (tmp_path / "scattered.csv",)}
    for name, (input_file, *more) in cases.items():
        options = quick if input_file == source else quick[:4]  # a file of samples is read whole
        assert _reconstruct(input_file, "--out", tmp_path / name, *options, *more) == 0
    used = {name: json.loads((tmp_path / name / "reconstruction.json").read_text())["refine"]["coverage_k"]
            for name in cases}
    assert used == {"bins": 0, "uniform": DEVICE_COVERAGE_K, "astm": DEVICE_COVERAGE_K, "csv": 0}
    # `full` was not judged with the weights: off unless asked for
    assert _reconstruct(source, "--out", tmp_path / "full", "--model", run_dir, "--samples", 300, "--pattern",
                        "uniform") == 0
    assert json.loads((tmp_path / "full" / "reconstruction.json").read_text())["refine"]["coverage_k"] == 0


def test_a_failure_while_writing_leaves_no_output(run_dir, toy_materials, tmp_path, monkeypatch):
    from frenbrdf.material import outputs as reconstruct_outputs

    def broken(path, image):
        raise OSError("disk full")

    monkeypatch.setattr(reconstruct_outputs, "save_png", broken)
    with pytest.raises(SystemExit):
        _reconstruct(sorted(toy_materials.glob("*.binary"))[0], "--out", tmp_path / "out", "--model", run_dir,
                     "--samples", 200, "--refine", "none")
    assert list(tmp_path.iterdir()) == []  # neither the folder nor its staging copy


def test_a_bad_model_file_is_named(toy_materials, tmp_path, capsys, run_dir):
    source = sorted(toy_materials.glob("*.binary"))[0]
    corrupt = tmp_path / "corrupt.pt"
    corrupt.write_bytes(b"garbage")
    with pytest.raises(SystemExit):
        _reconstruct(source, "--out", tmp_path / "o", "--model", corrupt)
    assert "corrupt.pt: not a readable frenbrdf checkpoint" in capsys.readouterr().err
    checkpoint = torch.load(run_dir / "best.pt", weights_only=True)
    future = tmp_path / "future" / "best.pt"
    future.parent.mkdir()
    torch.save({**checkpoint, "format": 99}, future)
    with pytest.raises(SystemExit):
        _reconstruct(source, "--out", tmp_path / "o", "--model", future.parent)
    assert "best.pt: checkpoint format 99" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


# --------------------------------------------------------------------------- packing a model


def test_a_packed_model_reconstructs_as_its_run(run_dir, model, material, tmp_path):
    sizes = pretrained.pack_pretrained(run_dir, tmp_path / "packed", card={"data": "toy"})
    assert sum(sizes.values()) < 5e6
    packed = frenbrdf.Model.pretrained(tmp_path / "packed")
    assert packed.card["version"] == pretrained.VERSION and packed.card["data"] == "toy"
    z = model.encode(material.values, (material.wi, material.wo))
    z_packed = packed.encode(material.values, (material.wi, material.wo))
    np.testing.assert_allclose(z_packed, z, atol=0.02 * np.abs(z).max())  # float16 weights
    reference, restored = model.mapping.reference, packed.mapping.reference
    relative = np.abs((restored + model.mapping.epsilon) / (reference + model.mapping.epsilon) - 1)
    assert relative.max() < 2e-4


def test_a_packing_that_fails_midway_leaves_the_old_model_whole(run_dir, tmp_path, monkeypatch):
    packed = tmp_path / "packed"
    pretrained.pack_pretrained(run_dir, packed, card={"data": "old"})
    before = {path.name: path.read_bytes() for path in packed.iterdir()}

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(pretrained.np, "savez_compressed", full_disk)  # after model.pt is written
    with pytest.raises(OSError, match="No space left"):
        pretrained.pack_pretrained(run_dir, packed, card={"data": "new"}, half=False)
    assert {path.name: path.read_bytes() for path in packed.iterdir()} == before  # no temporary file left either


def test_pack_mapping_round_trips():
    rng = np.random.default_rng(0)
    per_channel = {"reference": np.array([0.1, 0.2, 0.3]), "epsilon": 0.002, "offset": 1.0}
    back = pretrained.unpack_mapping(pretrained.pack_mapping(per_channel))
    np.testing.assert_array_equal(back["reference"], per_channel["reference"])
    assert back["offset"] == 1.0
    table = np.exp(rng.normal(size=(3, 90, 90, 180)).cumsum(-1) * 0.05)
    back = pretrained.unpack_mapping(pretrained.pack_mapping({"reference": table, "epsilon": 0.002}))
    assert np.abs((back["reference"] + 0.002) / (table + 0.002) - 1).max() < 2e-4


def test_missing_or_foreign_packed_files_are_named(run_dir, tmp_path):
    with pytest.raises(FileNotFoundError, match=r"no pretrained model: .*lacks model\.pt, mapping\.npz, card\.json"):
        frenbrdf.Model.pretrained(tmp_path)
    pretrained.pack_pretrained(run_dir, tmp_path / "packed")
    saved = torch.load(tmp_path / "packed" / "model.pt", weights_only=True)
    torch.save({**saved, "format": 7}, tmp_path / "packed" / "model.pt")
    with pytest.raises(ValueError, match=r"model\.pt: packed-model format 7"):
        frenbrdf.Model.pretrained(tmp_path / "packed")
    (tmp_path / "packed" / "model.pt").write_bytes(b"garbage")
    with pytest.raises(ValueError, match=r"model\.pt: not a readable packed model"):
        frenbrdf.Model.pretrained(tmp_path / "packed")


def test_packing_never_replaces_files_that_are_not_a_packed_models(run_dir, tmp_path):
    before = (Path(run_dir) / "mapping.npz").read_bytes()
    with pytest.raises(ValueError, match=r"holds mapping\.npz, not a packed model's files"):
        pretrained.pack_pretrained(run_dir, run_dir)  # a run folder: its mapping.npz stays
    assert (Path(run_dir) / "mapping.npz").read_bytes() == before
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "card.json").write_text('{"mine": true}')
    with pytest.raises(ValueError, match=r"holds card\.json, not a packed model's files"):
        pretrained.pack_pretrained(run_dir, notes)
    assert (notes / "card.json").read_text() == '{"mine": true}'
    pretrained.pack_pretrained(run_dir, tmp_path / "packed")
    with pytest.raises(ValueError, match="is the input"):  # what a model is assembled from is never its destination
        pretrained.check_pack_destination(tmp_path / "packed", inputs=[tmp_path / "packed"])


@pytest.mark.slow
def test_chart_8_runs_on_a_tiny_run(run_dir, tmp_path):
    report = script_module("chart_refine").refine_chart(run_dir, tmp_path, latent_steps=(2,), full_latent_steps=2,
                                                       weight_steps=(2,), fit_epochs=(), max_materials=1,
                                                       resolution=32, progress=False)
    assert {row["family"] for row in report["points"]} == {"encoder", "latent", "full"}
    assert all((tmp_path / f"chart8_refine.{suffix}").exists() for suffix in ("png", "csv", "json"))


@pytest.mark.slow
def test_chart_8c_measures_every_schedule(run_dir, tmp_path):
    schedules = script_module("chart_refine_schedules")
    points = [(family, label, dataclasses.replace(config, latent_steps=min(config.latent_steps, 2),
                                                  weight_steps=min(config.weight_steps, 2)))
              for family, label, config in schedules.POINTS]
    report = script_module("chart_refine").refine_chart(run_dir, tmp_path, max_materials=1, resolution=32,
                                                       progress=False, points=points, draw_chart=schedules.draw,
                                                       name="chart8c")
    assert [row["budget"] for row in report["points"]] == [label for _, label, _ in schedules.POINTS]
    assert all((tmp_path / f"chart8c.{suffix}").exists() for suffix in ("png", "csv", "json"))


def test_real_measurement_study_runs_on_a_bsdf(run_dir, tmp_path):
    measurement = tmp_path / "flat_rgb.bsdf"
    measurement.write_bytes(tensor_file(flat_material()))
    study = script_module("real_measurements")
    assert study.main([str(measurement), "--model", str(run_dir), "--samples", "300", "--resolution", "16",
                       "--fit-epochs", "0", "--out", str(tmp_path / "out")]) == 0
    report = json.loads((tmp_path / "out" / "real.json").read_text())
    rows = report["materials"]["flat_rgb"]
    assert set(rows) == {"encoder", "latent", "full"}
    assert all(np.isfinite(row["psnr"]) and 0 < row["seconds"] < 60 for row in rows.values())


def test_latent_reach_study_splits_the_error_at_the_published_fit(run_dir, tmp_path):
    from .conftest import random_layers, write_keras_h5

    measurement = tmp_path / "flat_rgb.bsdf"
    measurement.write_bytes(tensor_file(flat_material()))
    write_keras_h5(tmp_path / "flat_rgb.h5", random_layers([6, 8, 3], seed=1))
    study = script_module("latent_reach")
    assert study.main([str(measurement), "--fits", str(tmp_path), "--model", str(run_dir), "--samples", "300",
                       "--steps", "3", "--draws", "0", "1", "--resolution", "16", "--out", str(tmp_path / "out")]) == 0
    rows = json.loads((tmp_path / "out" / "reach.json").read_text())["rows"]
    assert [(row["material"], row["draw"]) for row in rows] == [("flat_rgb", 0), ("flat_rgb", 1)]
    pairs = {f"{a} vs {b}" for a, b in study.PAIRS}
    assert all(set(row["scores"]) == pairs for row in rows)
    assert all(np.isfinite(m["psnr"]) and m["delta_e"] >= 0 for row in rows for m in row["scores"].values())
    fixed = "fit vs measurement"  # no sampling in it: the same in every draw
    assert rows[0]["scores"][fixed] == rows[1]["scores"][fixed]
    assert "| mean |" in (tmp_path / "out" / "reach.md").read_text() and (tmp_path / "out" / "reach.png").exists()


def test_full_limits_study_measures_every_variant_and_the_table(run_dir, toy_materials, tmp_path):
    measurement = tmp_path / "flat_rgb.bsdf"
    measurement.write_bytes(tensor_file(flat_material()))
    study = script_module("full_limits")
    assert study.main([str(measurement), "--model", str(run_dir), "--samples", "200", "400", "--weight-steps", "2",
                       "5", "--widths", "0", "40", "--draws", "0", "1", "--resolution", "16",
                       "--out", str(tmp_path / "out")]) == 0
    report = json.loads((tmp_path / "out" / "limits.json").read_text())
    rows = report["materials"]["flat_rgb"]
    assert set(rows) == {"table lookup", *(f"{n} samples, {k} weight steps{w}" for n in (200, 400) for k in (2, 5)
                                           for w in ("", ", width 40"))}
    assert all(m["seconds"] > 0 for k, v in rows.items() if k != "table lookup" for m in v)
    assert len(rows["table lookup"]) == 1 and all(len(v) == 2 for k, v in rows.items() if k != "table lookup")
    assert all(np.isfinite(m["psnr"]) for v in rows.values() for m in v)
    assert "| 200 samples, 2 weight steps |" in (tmp_path / "out" / "limits.md").read_text()
    assert (tmp_path / "out" / "limits.png").exists()
    # A MERL table is its own truth: no table-lookup row, and it mixes with a measurement.
    table = sorted(toy_materials.glob("*.binary"))[0]
    assert study.main([str(table), str(measurement), "--model", str(run_dir), "--samples", "200", "--weight-steps",
                       "2", "--resolution", "16", "--out", str(tmp_path / "mixed")]) == 0
    mixed = json.loads((tmp_path / "mixed" / "limits.json").read_text())["materials"]
    assert "table lookup" not in mixed[table.stem] and "table lookup" in mixed["flat_rgb"]


def test_refine_timing_times_this_tree_against_a_commit(run_dir, toy_materials, tmp_path, capsys):
    import subprocess

    if subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True).returncode:
        pytest.skip("not a git checkout: the timing study reads earlier commits with git show")
    measurement = tmp_path / "flat_rgb.bsdf"
    measurement.write_bytes(tensor_file(flat_material()))
    study = script_module("refine_timing")
    table = sorted(toy_materials.glob("*.binary"))[0]
    assert study.main([str(measurement), str(table), "--model", str(run_dir), "--budget", "latent", "--samples",
                       "200", "--repeats", "2", "--against", "HEAD"]) == 0
    summary = capsys.readouterr().out.split("best of 2:")[1]
    assert "this tree  mean" in summary and "HEAD  mean" in summary and table.stem in summary
    assert study.main([str(table), "--model", str(run_dir), "--samples", "200", "--repeats", "1", "--against", "HEAD",
                       "--width", "40", "--weight-steps", "3"]) == 0  # the same work where budgets differ
    assert "full {'width': 40, 'weight_steps': 3}" in capsys.readouterr().out
    with pytest.raises(SystemExit, match="cannot read"):
        study.main([str(measurement), "--model", str(run_dir), "--against", "no-such-commit"])


def test_model_comparison_pairs_models_and_skips_what_a_model_trained_on(run_dir, toy_materials, tmp_path):
    measurement = tmp_path / "flat_rgb.bsdf"
    measurement.write_bytes(tensor_file(flat_material()))
    tables = sorted(toy_materials.glob("*.binary"))[:2]
    study = script_module("compare_models")
    config = tmp_path / "config.json"  # the second table comes as a training config's held-out material
    config.write_text(json.dumps({"holdout": [tables[1].stem]}))
    assert study.main(["--models", str(run_dir), str(run_dir), "--labels", "base", "same/0", "--measurements",
                       str(measurement), "--tables", str(tables[0]), "--held-out", str(config), str(toy_materials),
                       "--samples", "300", "--resolution", "16", "--trained-on", f"same/0={tables[0].stem}",
                       "--group", f"both={tables[0].stem},flat_rgb", "--out", str(tmp_path / "out")]) == 0
    report = json.loads((tmp_path / "out" / "compare.json").read_text())
    assert {r["material"] for r in report["rows"]} == {"flat_rgb", tables[0].stem, tables[1].stem}
    assert not [r for r in report["rows"] if r["model"] == "same/0" and r["material"] == tables[0].stem]
    for budget in ("none", "latent"):  # the same model on the same samples: no change, and one table left out
        same = report["summary"]["tables"][budget]["same"]
        assert same["materials"] == 1 and same["psnr_change"]["mean"] == pytest.approx(0, abs=1e-9)
        assert report["summary"]["measured"][budget]["same"]["delta_e_change"]["mean"] == pytest.approx(0, abs=1e-9)
    both = report["summary"]["both"]["none"]  # a group of a table and a measurement, summarised apart
    assert both["base"]["materials"] == 2 and both["same"]["materials"] == 1  # same/0 trained on the table
    with pytest.raises(SystemExit):
        study.main(["--models", str(run_dir), "--labels", "base", "--trained-on", "other=x", "--out", str(tmp_path)])
    with pytest.raises(SystemExit):  # a group's material that is not scored
        study.main(["--models", str(run_dir), "--labels", "base", "--tables", str(tables[0]), "--group", "g=nothing",
                    "--out", str(tmp_path)])


def test_model_comparison_takes_a_budget_with_fields_changed():
    study = script_module("compare_models")
    config = study.budget_config("latent@latent_steps=600,starts=3,keep_order=false,seconds=none")
    assert config == dataclasses.replace(BUDGETS["latent"], latent_steps=600, starts=3, keep_order=False)
    for wrong, message in (("latent@steps=600", "not FIELD=VALUE"), ("latent@latent_steps=", "not FIELD=VALUE"),
                           ("latent@starts=0", "starts must be"), ("most", "refine must be one of")):
        with pytest.raises(ValueError, match=message):
            study.budget_config(wrong)


def test_model_comparison_takes_a_baseline_of_several_runs(run_dir, toy_materials, tmp_path):
    """A baseline labelled NAME/RUN is its runs' mean per material (it once compared with no rows: NaN)."""
    table = sorted(toy_materials.glob("*.binary"))[0]
    study = script_module("compare_models")
    assert study.main(["--models", str(run_dir), str(run_dir), str(run_dir), "--labels", "base/0", "base/1", "other/0",
                       "--tables", str(table), "--samples", "300", "--resolution", "16", "--budgets", "none",
                       "--out", str(tmp_path / "out")]) == 0
    summary = json.loads((tmp_path / "out" / "compare.json").read_text())["summary"]["tables"]["none"]
    assert summary["base"]["runs"] == ["base/0", "base/1"] and summary["base"]["psnr_run_sd"] == pytest.approx(0)
    assert summary["other"]["psnr_change"]["mean"] == pytest.approx(0, abs=1e-9)


def test_model_comparison_keeps_a_table_and_a_measurement_of_one_name_apart():
    """An RGL fit's table and its .bsdf share a name; each group summarises its own rows (they were once pooled)."""
    study = script_module("compare_models")
    rows = [{"model": model, "material": "paper_blue_rgb", "group": group, "budget": "none", "psnr": psnr,
             "delta_e": 1.0} for model, group, psnr in (("a", "tables", 30.0), ("b", "tables", 32.0),
                                                         ("a", "measured", 20.0), ("b", "measured", 10.0))]
    groups = {"tables": ["paper_blue_rgb"], "measured": ["paper_blue_rgb"], "both": ["paper_blue_rgb"]}
    summary = study.summarise(rows, "a", groups, ("none",))
    assert summary["tables"]["none"]["b"]["psnr"] == 32.0 and summary["measured"]["none"]["b"]["psnr"] == 10.0
    assert summary["tables"]["none"]["b"]["psnr_change"]["mean"] == pytest.approx(2.0)
    assert summary["both"]["none"]["b"]["psnr"] == 21.0  # a group of names takes the rows of both


def test_model_comparison_reads_materials_through_each_pattern_and_count(run_dir, toy_materials, tmp_path):
    table = sorted(toy_materials.glob("*.binary"))[0]
    study = script_module("compare_models")
    assert study.main(["--models", str(run_dir), "--labels", "base", "--tables", str(table), "--patterns",
                       "merl-bins", "in-plane", "--samples", "300", "200", "--refine-counts", "300",
                       "--resolution", "16", "--out", str(tmp_path / "out")]) == 0
    report = json.loads((tmp_path / "out" / "compare.json").read_text())
    done = {(r["pattern"], r["count"], r["budget"]) for r in report["rows"]}
    assert done == {(p, c, "none") for p in ("merl-bins", "in-plane") for c in (300, 200)} | {
        ("merl-bins", 300, "latent"), ("in-plane", 300, "latent")}  # refined at 300 samples only
    assert set(report["summary"]["tables @ in-plane × 200"]) == {"none"}
    in_plane = [r["psnr"] for r in report["rows"] if r["pattern"] == "in-plane" and r["count"] == 300]
    bins = [r["psnr"] for r in report["rows"] if r["pattern"] == "merl-bins" and r["count"] == 300]
    assert in_plane != bins  # another pattern's samples, not the random bins again
    text = (tmp_path / "out" / "compare.md").read_text()
    assert "| in-plane × 200 |" in text and "**tables, latent**" in text


@pytest.mark.slow  # trains, evaluates and packs: about a minute on a shared 2-core machine
def test_the_pretrained_bench_builds_a_tiny_model(toy_materials, tmp_path):
    config = tmp_path / "tiny.json"
    config.write_text(json.dumps({"epochs": 1, "batch_materials": 2, "context_samples": 128, "query_samples": 128,
                                  "cache_dir": str(tmp_path / "cache"), "loss": {"eta": 0},
                                  "model": {"nbrdf": {"hidden": [8]}, "encoder": {"hidden": [16], "latent": 4},
                                            "decoder": {"hidden": [16]}}}))
    card = script_module("train_shipped_model").build(str(config), [toy_materials], tmp_path / "work", tmp_path / "packed",
                                            tmp_path / "card.md", progress=False)
    assert frenbrdf.Model.pretrained(tmp_path / "packed").card["held_out"] == card["held_out"]
    assert abs(card["held_out"]["packed"]["psnr"] - card["held_out"]["float32"]["psnr"]) < 0.1
    assert "| PSNR (dB) |" in (tmp_path / "card.md").read_text()
    work = tmp_path / "work"
    sources = json.loads((work / "sources.json").read_text())
    assert list(sources) == [toy_materials.name] == card["data"]
    test_count = card["materials"]["test"]
    assert card["held_out_by_source"][toy_materials.name]["n"] == test_count
    # Its encoders packed from the same work folder, as release/train_shipped_model.sh does last.
    member = frenbrdf.training.train(frenbrdf.training.load_config(
        str(config), data=str(work / "data"), out=str(tmp_path / "member"), seed=1,
        decoder_from=str(tmp_path / "packed"), progress=False))
    assert script_module("pack_encoder_mean").main([
        "--base", str(tmp_path / "packed"), "--members", str(member.path), "--choice", "best-fit", "--version", "t",
        "--work", str(work), "--dest", str(tmp_path / "packed-2"), "--card", str(tmp_path / "card-2.md")]) == 0
    card = frenbrdf.Model.pretrained(tmp_path / "packed-2").card
    assert card["encoders"]["members"] == [str(member.path)] and card["version"] == "t"
    assert card["held_out_by_source"][toy_materials.name]["n"] == test_count
    # Then second looks for that model, both packed, their answers averaged (one epoch each: the pipeline, not
    # quality).
    looks = [tmp_path / f"look-{seed}" for seed in (1, 2)]
    for seed, look in enumerate(looks, start=1):
        assert script_module("second_look").main([
            "train", str(config), str(work / "data"), "--base", str(tmp_path / "packed-2"), "--out", str(look),
            "--epochs", "1", "--seed", str(seed), "--quiet"]) == 0
    assert script_module("pack_second_look").main([
        "--base", str(tmp_path / "packed-2"), "--looks", *map(str, looks), "--mean", "--version", "t2", "--work",
        str(work), "--dest", str(tmp_path / "packed-3"), "--card", str(tmp_path / "card-3.md")]) == 0
    packed = frenbrdf.Model.pretrained(tmp_path / "packed-3")
    card = packed.card
    assert card["version"] == "t2" and card["second_look"]["runs"] == list(map(str, looks))
    assert packed.config.second_look.members == 2
    assert card["held_out_by_source"][toy_materials.name]["n"] == test_count
    assert "2 runs, their answers averaged" in (tmp_path / "card-3.md").read_text()


#: The PSNR (dB, metric renderer, refine="full") the shipped model must reach on a bank material.
#: What the shipped model must reach on a purple plastic it never saw (a bank drawn from another seed),
#: per refinement budget: (PSNR at least, ΔE at most). Measured: 27.1 dB / 3.4, 36.1 / 1.4, 41.8 / 0.4.
SHIPPED_QUALITY = {"none": (25.0, 5.0), "latent": (33.0, 2.0), "full": (38.0, 1.0)}


@pytest.mark.pretrained
def test_pretrained_model_ships_and_reconstructs(tmp_path):
    """The packaged model loads, is the documented version and gives an unseen purple plastic back purple."""
    from frenbrdf.data.synth import write_bank
    from frenbrdf.evaluation.evaluate import image_metrics
    from frenbrdf.render.renderer import Scene, material_mask, render

    missing = [name for name in (pretrained.MODEL_FILE, pretrained.MAPPING_FILE, pretrained.CARD_FILE)
               if not (pretrained.PACKAGE_DIR / name).exists()]
    assert not missing, (f"the package ships no pretrained model ({pretrained.PACKAGE_DIR} lacks {missing}): "
                         "run release/train_shipped_model.py and commit its files (docs/pretrained.md)")
    model = frenbrdf.Model.pretrained()
    assert model.card["version"] == pretrained.VERSION
    path = write_bank(tmp_path, n=4, seed=7, progress=False)[0]
    assert path.stem == "synth-000-purple-plastic"
    material = read_samples(path, samples=4000)
    scene = Scene(resolution=128)
    truth = render(material.table, scene)
    for budget, (least_psnr, most_delta_e) in SHIPPED_QUALITY.items():
        result = model.reconstruct(material.values, (material.wi, material.wo), refine=budget)
        metrics = image_metrics(truth, render(result.nbrdf, scene), material_mask(scene))
        assert metrics["psnr"] > least_psnr and metrics["delta_e"] < most_delta_e, (budget, metrics)


def _lit_from_above(values, wi, wo):
    """A non-reciprocal material: the toy's reflectance, brighter the higher the light (ω_i) stands."""
    return values * (0.4 + 1.2 * wi[:, 2:3])


def _in_both_orders(material, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The material's pairs, each reversed with probability ½, as a measurement is sampled."""
    reverse = np.random.default_rng(seed).random(len(material.values)) < 0.5
    return (np.where(reverse[:, None], material.wo, material.wi),
            np.where(reverse[:, None], material.wi, material.wo))


def test_full_keeps_the_order_of_a_pair_where_the_samples_hold_both(model, material):
    """A measurement need not be reciprocal; sampled in both orders, the weight stage fits an ordered NBRDF, which
    gives each order back, and fits closer than a reciprocal one."""
    from frenbrdf.models.nbrdf import pair_order

    wi, wo = _in_both_orders(material, 2)
    assert 0 < np.mean(pair_order(wi, wo) < 0) < 1
    values = _lit_from_above(material.values, wi, wo)
    config = RefineConfig(latent_steps=5, weight_steps=200, weight_lr=3e-3)
    ordered = model.reconstruct(values, (wi, wo), refine=config)
    reciprocal = model.reconstruct(values, (wi, wo), refine=dataclasses.replace(config, keep_order=False))
    assert ordered.nbrdf.ordered and not reciprocal.nbrdf.ordered
    assert ordered.losses["latent"] == reciprocal.losses["latent"]  # the order enters at the weight stage only
    assert ordered.losses["weights"] < 0.8 * reciprocal.losses["weights"]
    # Each order comes back: f(ω_i, ω_o) and f(ω_o, ω_i) differ as the material's do.
    forward, backward = ordered.nbrdf(wi, wo), ordered.nbrdf(wo, wi)
    truth_ratio = _lit_from_above(np.ones_like(values), wi, wo) / _lit_from_above(np.ones_like(values), wo, wi)
    assert np.corrcoef(np.log(forward.mean(-1) / backward.mean(-1)), np.log(truth_ratio[:, 0]))[0, 1] > 0.8
    np.testing.assert_allclose(reciprocal.nbrdf(wi, wo), reciprocal.nbrdf(wo, wi), rtol=1e-5, atol=1e-7)


def test_keep_order_is_a_bool():
    with pytest.raises(ValueError, match="keep_order must be True or False, got 'no'"):
        RefineConfig(weight_steps=5, keep_order="no")


def test_samples_in_one_order_keep_the_nbrdf_reciprocal(model, material):
    result = model.reconstruct(material.values, (material.wi, material.wo),
                               refine=RefineConfig(latent_steps=2, weight_steps=5))
    assert not result.nbrdf.ordered  # a MERL table's samples: every pair in the table's order


def test_an_ordered_nbrdf_saves_renders_and_writes_its_table_order(model, material, tmp_path):
    from frenbrdf.io.sampling import bin_directions
    from frenbrdf.models.nbrdf import NBRDF
    from frenbrdf.render import Scene, render_linear

    wi, wo = _in_both_orders(material, 3)
    nbrdf = model.reconstruct(_lit_from_above(material.values, wi, wo), (wi, wo),
                              refine=RefineConfig(latent_steps=2, weight_steps=100, weight_lr=3e-3)).nbrdf
    assert nbrdf.ordered
    write_material(tmp_path / "m.pt", nbrdf.weights())
    again = NBRDF.from_weights(read_material(tmp_path / "m.pt"))
    assert again.ordered
    np.testing.assert_array_equal(again(wi, wo), nbrdf(wi, wo))
    # Its table holds each pair in the table's order; in_table_order is the reciprocal NBRDF that agrees there.
    table_order = nbrdf.in_table_order()
    assert not table_order.ordered
    bins = np.flatnonzero(frenbrdf.valid_mask(material.table))[::997]
    bin_wi, bin_wo = bin_directions(bins)
    np.testing.assert_allclose(table_order(bin_wi, bin_wo), nbrdf(bin_wi, bin_wo), rtol=1e-5)
    assert not np.allclose(nbrdf(bin_wo, bin_wi), nbrdf(bin_wi, bin_wo), rtol=1e-3)
    np.testing.assert_allclose(nbrdf.merl_table().reshape(3, -1)[:, bins].T, nbrdf(bin_wi, bin_wo), rtol=1e-5)
    # The metric renderer evaluates each light's pair in its own order.
    scene = Scene(resolution=16)
    assert not np.allclose(render_linear(nbrdf, scene), render_linear(table_order, scene))


def test_coverage_weights_change_the_latent_stage_and_the_reported_loss_stays_unweighted(model, material):
    from frenbrdf.models.losses import samples_loss
    from frenbrdf.models.nbrdf import mapped_samples

    directions = (material.wi, material.wo)
    base = RefineConfig(latent_steps=20, latent_lr=0.05)
    plain = reconstruct(model, material.values, directions, refine=base)
    weighted = reconstruct(model, material.values, directions, refine=dataclasses.replace(base, coverage_k=8))
    assert not np.allclose(plain.z, weighted.z)
    mapped, coords, cos_in = mapped_samples(model.mapping, material.values, directions)
    with torch.no_grad():
        params = model.network.decoder(torch.from_numpy(weighted.z.astype(np.float32))[None])
    tensors = (torch.from_numpy(np.asarray(a, dtype=np.float32))[None] for a in (coords, mapped, cos_in))
    assert weighted.losses["latent"] == pytest.approx(samples_loss(params, *tensors, model.loss["kind"]), rel=1e-5)


def test_an_anchor_holds_the_start_where_the_samples_say_nothing(model, material):
    """Samples near the mirror only: `latent` moves the rest of the table freely; a heavy anchor keeps it near the
    encoder's decoding there, while the samples still fit nearly as well as without."""
    from frenbrdf.io.sampling import bin_directions
    from frenbrdf.models.coverage import index_space, uncovered_bins

    seen = index_space(material.wi, material.wo)[:, 0] < 0.4
    values, directions = material.values[seen], (material.wi[seen], material.wo[seen])
    base = RefineConfig(latent_steps=60, latent_lr=0.05)
    runs = {anchor: reconstruct(model, values, directions, refine=dataclasses.replace(base, anchor=anchor))
            for anchor in (0.0, 10.0)}
    start = reconstruct(model, values, directions, refine="none")
    unseen = bin_directions(uncovered_bins(*directions)[0])

    def moved(result):  # how far the NBRDF moved from the encoder's on the bins no sample saw
        return np.abs(np.log1p(result.nbrdf(*unseen)) - np.log1p(start.nbrdf(*unseen))).mean()

    assert moved(runs[10.0]) < 0.5 * moved(runs[0.0])
    assert runs[10.0].losses["latent"] < start.losses["encode"]


@pytest.mark.parametrize("ordered", [False, True], ids=["reciprocal", "ordered"])
def test_fold_edge_pairs_are_the_inputs_on_either_side_of_the_edge(ordered):
    """Each pair is the limit of the NBRDF's input just past and just before the edge it ties, at one (θ_h, θ_d)."""
    from frenbrdf.models.nbrdf import fold_edge_pairs, nbrdf_coordinates

    pairs = fold_edge_pairs(200, seed=3, ordered=ordered)
    assert pairs.shape == (200, 2, 6)
    theta_h = np.arctan2(pairs[:, 0, 0], pairs[:, 0, 2])
    theta_d = np.arctan2(np.abs(pairs[:, 0, 3]), pairs[:, 0, 5])
    edges = np.where(ordered & (np.arange(200) >= 100), np.pi, 0.0)  # an ordered NBRDF: φ_d = 0, then π
    for side, offset in ((0, 1e-6), (1, -1e-6)):
        phi_d = edges + np.where(edges > 0, -offset, offset)
        angles = np.stack([theta_h, np.zeros(200), theta_d, phi_d], axis=-1)
        wi, wo = frenbrdf.rusinkiewicz_to_directions(angles)
        assert (wi[:, 2] > 0).all() and (wo[:, 2] > 0).all()
        np.testing.assert_allclose(nbrdf_coordinates(wi, wo, ordered=ordered), pairs[:, side], atol=1e-5)
    np.testing.assert_array_equal(fold_edge_pairs(200, seed=3, ordered=ordered), pairs)
    assert fold_edge_pairs(0, seed=3).shape == (0, 2, 6)
    with pytest.raises(ValueError, match="count must be ≥ 0, got -1"):
        fold_edge_pairs(-1, seed=3)


@pytest.mark.parametrize("both_orders", [False, True], ids=["reciprocal", "ordered"])
def test_a_tie_closes_the_gap_across_the_fold_edge(model, material, both_orders):
    """`tie` pulls the refined NBRDF's two sides of the fold's edge together: the gap between them at the tied pairs
    (and at pairs it did not tie) shrinks, while the samples still fit."""
    from frenbrdf.models.nbrdf import fold_edge_pairs, nbrdf_forward

    wi, wo = _in_both_orders(material, 2) if both_orders else (material.wi, material.wo)
    values = _lit_from_above(material.values, wi, wo) if both_orders else material.values
    config = RefineConfig(latent_steps=5, weight_steps=300, weight_lr=3e-3)
    free = model.reconstruct(values, (wi, wo), refine=config)
    tied = model.reconstruct(values, (wi, wo), refine=dataclasses.replace(config, tie=1.0))
    assert tied.nbrdf.ordered == free.nbrdf.ordered == both_orders

    def gap(result, seed):
        pairs = torch.from_numpy(fold_edge_pairs(128, seed, both_orders).astype(np.float32))
        outputs = [nbrdf_forward(result.nbrdf.params, pairs[None, :, side]) for side in (0, 1)]
        return float((outputs[0] - outputs[1]).abs().mean())

    for seed in (0, 99):  # the tied pairs, and others
        assert gap(tied, seed) < 0.3 * gap(free, seed), seed
    assert tied.losses["weights"] < 2 * free.losses["weights"]


def test_a_tie_is_a_number_within_bounds():
    with pytest.raises(ValueError, match="tie must be a number from 0 to 100, got -1"):
        RefineConfig(weight_steps=5, tie=-1)
    with pytest.raises(ValueError, match="tie must be a number from 0 to 100, got True"):
        RefineConfig(weight_steps=5, tie=True)
    with pytest.raises(ValueError, match="it needs weight_steps > 0"):
        RefineConfig(latent_steps=5, tie=0.1)
