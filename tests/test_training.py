"""Training: a tiny run learns, resumes exactly, stops on NaN, refuses bad configs, runs under DDP."""

from __future__ import annotations

import itertools
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf import cli, presets, training
from frenbrdf.configs import to_dict
from frenbrdf.data.folders import list_materials, split_materials
from frenbrdf.io import checkpoints
from frenbrdf.io.checkpoints import load as load_checkpoint
from frenbrdf.io.outputs import MARKER
from frenbrdf.models.losses import LossConfig
from frenbrdf.training import Run, TrainingDiverged, config_for, load_config, train

from .conftest import tiny


def test_tiny_frenbrdf_training_loss_falls(toy_materials, tmp_path):
    result = train(tiny("frenbrdf", toy_materials, tmp_path / "run", epochs=15, split=(0.5, 0.25, 0.25)))
    untrained = result.history[0]
    assert untrained["epoch"] == -1
    assert result.best_val < 0.8 * untrained["val_rec"], [epoch["val_rec"] for epoch in result.history]
    assert all(epoch["train_fre"] > 0 for epoch in result.history[1:])
    # The strength η gives L_fre, logged every epoch: ‖∇(η·L_fre)‖ / ‖∇L_rec‖.
    assert all(0 < epoch["train_gradient_ratio"] < math.inf for epoch in result.history[1:])


@pytest.mark.parametrize("method", ["frenbrdf", "nbrdf", "hyperbrdf"])
def test_every_method_writes_a_loadable_run(method, toy_materials, tmp_path):
    cfg = tiny(method, toy_materials, tmp_path / method, epochs=2)
    result = train(cfg)
    assert ("train_fre" in result.history[-1]) == (method == "frenbrdf")
    for name in ("config.json", "split.json", "history.json", "mapping.npz", "best.pt", "last.pt"):
        assert (result.path / name).exists(), name
    assert [p.name for p in result.path.glob(".*")] == [MARKER], "temporary files left behind"
    split = json.loads((result.path / "split.json").read_text())
    assert len(split["train"]) + len(split["val"]) + len(split["test"]) == 8
    model = frenbrdf.Model.load(result.path)
    assert model.method == method and model.config.nbrdf.hidden == cfg.model.nbrdf.hidden
    # The run folder, reopened, is the one training returned.
    run = Run(result.path)
    assert run.config == cfg and run.split.to_json() == split and run.history == result.history
    assert run.best_epoch == load_checkpoint(run.path / "best.pt")["epoch"]


def test_checkpoints_hold_no_mapping_and_format_1_run_folders_still_load(toy_materials, tmp_path):
    run = train(tiny("frenbrdf", toy_materials, tmp_path / "run", epochs=1))
    checkpoint = load_checkpoint(run.path / "best.pt")
    assert checkpoint["format"] == checkpoints.FORMAT == 2 and "mapping" not in checkpoint
    model = run.model()
    # A format-1 checkpoint carried the mapping inside it, and its folder had no mapping.npz.
    old = tmp_path / "old"
    old.mkdir()
    mapping = {"reference": torch.from_numpy(model.mapping.state()["reference"]), "epsilon": model.mapping.epsilon}
    torch.save({**checkpoint, "format": 1, "mapping": mapping}, old / "best.pt")
    loaded = frenbrdf.Model.load(old)
    np.testing.assert_array_equal(loaded.mapping.reference, model.mapping.reference)
    # A format-2 checkpoint copied without its mapping says what is missing.
    lonely = tmp_path / "lonely"
    lonely.mkdir()
    (lonely / "best.pt").write_bytes((run.path / "best.pt").read_bytes())
    with pytest.raises(FileNotFoundError, match="mapping.npz"):
        frenbrdf.Model.load(lonely)
    torch.save({**checkpoint, "format": 99}, old / "future.pt")
    with pytest.raises(ValueError, match="format 99"):
        frenbrdf.Model.load(old / "future.pt")


def test_a_folder_that_is_not_a_run_is_refused_by_name(tmp_path):
    with pytest.raises(FileNotFoundError, match="not a training run folder"):
        Run(tmp_path)


def test_presets_come_from_one_registry():
    hyper = config_for("hyperbrdf")
    assert (hyper.loss.kind, hyper.lr, hyper.grad_clip, hyper.model.nbrdf.hidden) == ("mse", 5e-5, 1.0, (60,) * 4)
    # HyperBRDF's own mapping ln(1 + ratio) and weight penalty (mean over all weights), as its main.py runs.
    assert (hyper.model.mapping.form, hyper.loss.weight_penalty) == ("one_plus_ratio", "all")
    assert (config_for("frenbrdf").model.mapping.form, config_for("nbrdf").loss.weight_penalty) == ("ratio",
                                                                                                   "per_tensor")
    assert config_for("nbrdf").loss.eta == 0 and config_for("frenbrdf").loss.eta == LossConfig().eta > 0
    demo = config_for("hyperbrdf", training="demo", epochs=7)
    assert (demo.epochs, demo.context_samples, demo.lr) == (7, presets.TRAINING["demo"]["context_samples"], 5e-5)
    assert config_for("frenbrdf", training="demo").lr == config_for("frenbrdf").lr
    with pytest.raises(ValueError, match="training preset"):
        config_for("frenbrdf", training="marathon")
    with pytest.raises(ValueError, match="unknown key"):
        config_for("frenbrdf", epoch=3)


def test_resume_reproduces_the_uninterrupted_run(toy_materials, tmp_path):
    whole = train(tiny("frenbrdf", toy_materials, tmp_path / "whole"))
    train(tiny("frenbrdf", toy_materials, tmp_path / "parts", epochs=2))
    resumed = train(tiny("frenbrdf", toy_materials, tmp_path / "parts"), resume=True)

    def measured(history):  # the wall time differs between two runs; every number measured must not
        return [{key: value for key, value in entry.items() if key != "seconds"} for entry in history]

    assert measured(resumed.history) == measured(whole.history)
    assert resumed.history[3]["seconds"] > resumed.history[2]["seconds"]  # the clock carries over the resume
    a, b = load_checkpoint(tmp_path / "whole" / "last.pt"), load_checkpoint(tmp_path / "parts" / "last.pt")
    for name, tensor in a["model"].items():
        assert torch.equal(tensor, b["model"][name]), name


def test_nan_loss_stops_with_the_step_and_term_and_keeps_the_checkpoint(toy_materials, tmp_path, monkeypatch):
    cfg = tiny("frenbrdf", toy_materials, tmp_path / "run", epochs=3)
    calls = {"n": 0}
    real = training.step.reconstruction_loss

    def poisoned(*args, **kwargs):
        value = real(*args, **kwargs)
        if torch.is_grad_enabled():  # a training step, not validation
            calls["n"] += 1
            if calls["n"] == 4:  # 2 steps per epoch: the second step of epoch 1
                return value * float("nan")
        return value

    monkeypatch.setattr(training.step, "reconstruction_loss", poisoned)
    with pytest.raises(TrainingDiverged, match=r"step 3: loss term\(s\) \['rec'\].*the last good checkpoint is kept"):
        train(cfg)
    checkpoint = load_checkpoint(tmp_path / "run" / "last.pt")
    assert checkpoint["epoch"] == 0
    assert all(torch.isfinite(t).all() for t in checkpoint["model"].values())


def test_a_loss_lost_at_the_first_step_says_no_checkpoint_is_kept(toy_materials, tmp_path, monkeypatch):
    cfg = tiny("frenbrdf", toy_materials, tmp_path / "run", epochs=3)
    real = training.step.reconstruction_loss
    monkeypatch.setattr(training.step, "reconstruction_loss", lambda *a, **k: real(*a, **k) * float("nan"))
    with pytest.raises(TrainingDiverged, match=r"step 0: .*stopped, before any checkpoint was written"):
        train(cfg)
    assert not (tmp_path / "run" / "last.pt").exists()


def test_a_huge_eta_trains_without_nan(toy_materials, tmp_path):
    """Adam is invariant to the scale of the loss: η = 1e12 lets L_fre dominate but stays finite."""
    cfg = tiny("frenbrdf", toy_materials, tmp_path / "run", epochs=2)
    cfg.loss.eta = 1e12
    result = train(cfg)
    assert all(math.isfinite(value) for epoch in result.history for value in epoch.values())


def test_bad_configs_fail_before_any_work(toy_materials, tmp_path):
    with pytest.raises(ValueError, match="method must be one of"):
        config_for("gan")
    with pytest.raises(ValueError, match="epochs must be ≥ 1"):
        config_for("frenbrdf", epochs=0)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        train(tiny("nbrdf", tmp_path / "absent", tmp_path / "run"))
    with pytest.raises(ValueError, match="no material files"):
        train(tiny("nbrdf", tmp_path, tmp_path / "run"))
    two = tmp_path / "two"
    two.mkdir()
    for path in list_materials(toy_materials)[:2]:
        (two / path.name).symlink_to(path)
    with pytest.raises(ValueError, match="at least 3 materials"):
        train(tiny("nbrdf", two, tmp_path / "run"))
    broken = tmp_path / "broken"
    broken.mkdir()
    for path in list_materials(toy_materials)[:4]:
        (broken / path.name).symlink_to(path)
    (broken / "truncated.binary").write_bytes(list_materials(toy_materials)[0].read_bytes()[:1000])
    names = [path.stem for path in list_materials(broken)]
    seed = next(seed for seed in range(100) if "truncated" not in split_materials(names, seed).test)
    with pytest.raises(frenbrdf.MerlFormatError, match="truncated.binary"):
        train(tiny("nbrdf", broken, tmp_path / "run", seed=seed))
    config_file = tmp_path / "config.json"
    config_file.write_text(json.dumps({"epochs": 2, "model": {"nbrdf": {"hiden": [8]}}}))
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['hiden'\]"):
        load_config(config_file)
    config_file.write_text(json.dumps({"method": "hyperbrdf", "epochs": 2}))
    loaded = load_config(config_file, data="d", out="o")
    assert loaded.model.nbrdf.hidden == (60, 60, 60, 60) and loaded.epochs == 2 and loaded.lr == 5e-5
    assert not (tmp_path / "run").exists()


def test_cli_train_and_resume(toy_materials, tmp_path, capsys):
    config_file = tmp_path / "tiny.json"
    config_file.write_text(json.dumps(to_dict(tiny("nbrdf", toy_materials, tmp_path / "run", epochs=1))))
    argv = ["train", "--config", str(config_file), "--json", "--quiet"]
    assert cli.main(argv) == 0
    assert json.loads(capsys.readouterr().out)["best_epoch"] == 0
    assert cli.main([*argv, "--epochs", "2", "--resume"]) == 0
    assert json.loads(capsys.readouterr().out)["best_epoch"] in (0, 1)
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["train", "--data", str(tmp_path / "absent"), "--out", str(tmp_path / "x"), "--quiet"])
    assert exit_info.value.code == 2
    assert "does not exist" in capsys.readouterr().err


def test_a_resume_without_a_config_continues_the_runs_own(toy_materials, tmp_path, capsys):
    """Only what is given changes: a resume asked for more epochs keeps the run's training length preset, lr and all."""
    out = tmp_path / "run"
    argv = ["train", "--data", str(toy_materials), "--out", str(out), "--quiet"]
    assert cli.main([*argv, "--training", "demo", "--epochs", "1", "--render-every", "0"]) == 0
    before = json.loads((out / "config.json").read_text())
    assert cli.main([*argv, "--epochs", "2", "--resume"]) == 0
    after = json.loads((out / "config.json").read_text())
    assert after["epochs"] == 2 and {**after, "epochs": 1} == before
    with pytest.raises(SystemExit) as exit_info:
        cli.main([*argv, "--training", "sweep", "--resume"])
    assert exit_info.value.code == 2 and "a resume continues the run's own config" in capsys.readouterr().err


DDP_SCRIPT = """
import sys, torch
from tests.conftest import tiny
from frenbrdf.training import train
from pathlib import Path
cfg = tiny("frenbrdf", Path(sys.argv[1]), Path(sys.argv[2]), epochs=2)
cfg.batch_materials = 4
train(cfg)
"""


def test_ddp_on_two_cpu_processes_equals_one_process(toy_materials, tmp_path):
    root = Path(__file__).resolve().parents[1]
    script = tmp_path / "ddp_train.py"
    script.write_text(DDP_SCRIPT)
    env = {**os.environ, "PYTHONPATH": str(root), "OMP_NUM_THREADS": "1"}
    single = subprocess.run([sys.executable, str(script), str(toy_materials), str(tmp_path / "single")],
                            env=env, cwd=root, capture_output=True, text=True, timeout=300)
    assert single.returncode == 0, single.stderr[-2000:]
    ddp = subprocess.run([sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node=2",
                          str(script), str(toy_materials), str(tmp_path / "ddp")],
                         env=env, cwd=root, capture_output=True, text=True, timeout=300)
    assert ddp.returncode == 0, ddp.stderr[:3000]
    a, b = load_checkpoint(tmp_path / "single" / "last.pt"), load_checkpoint(tmp_path / "ddp" / "last.pt")
    # Same samples, same initialisation; only the order of the gradient sums differs.
    for name, tensor in a["model"].items():
        torch.testing.assert_close(b["model"][name], tensor, rtol=1e-4, atol=1e-5)


def test_cli_trains_several_seeds_into_one_folder_each(toy_materials, tmp_path, capsys):
    config_file = tmp_path / "tiny.json"
    config_file.write_text(json.dumps(to_dict(tiny("nbrdf", toy_materials, tmp_path / "unused", epochs=1))))
    assert cli.main(["train", "--config", str(config_file), "--out", str(tmp_path / "runs"), "--seeds", "0", "3",
                     "--quiet", "--json"]) == 0
    runs = [Run(tmp_path / "runs" / f"seed-{seed}") for seed in (0, 3)]
    assert [run.config.seed for run in runs] == [0, 3] and runs[0].split != runs[1].split
    with pytest.raises(SystemExit):
        cli.main(["train", "--data", str(toy_materials), "--out", str(tmp_path / "x"), "--seed", "1", "--seeds", "2"])
    assert "not both" in capsys.readouterr().err


def test_holdout_makes_the_matching_family_the_test_split(toy_materials, tmp_path, capsys):
    names = [path.stem for path in list_materials(toy_materials)]
    split = split_materials(names, 0, (0.7, 0.1, 0.2), holdout=["toy-0[01]", "*-07"])
    assert split.test == ("toy-00", "toy-01", "toy-07")
    assert sorted(split.train + split.val) == sorted(set(names) - set(split.test)) and len(split.val) == 1
    with pytest.raises(ValueError, match="matches none"):
        split_materials(names, 0, holdout=["*fabric*"])
    with pytest.raises(ValueError, match="leaving 1 for training"):
        split_materials(names, 0, holdout=["toy-0[0-6]"])
    out = tmp_path / "run"
    config_file = tmp_path / "tiny.json"
    config_file.write_text(json.dumps(to_dict(tiny("nbrdf", toy_materials, out, epochs=1))))
    assert cli.main(["train", "--config", str(config_file), "--holdout", "toy-0[01]", "--quiet", "--json"]) == 0
    capsys.readouterr()
    run = Run(out)
    assert run.config.holdout == ("toy-0[01]",) and run.split.test == ("toy-00", "toy-01")


def test_a_tiny_run_with_every_augmentation_and_regulariser_logs_finite_losses(toy_materials, tmp_path):
    cfg = tiny("frenbrdf", toy_materials, tmp_path / "run", epochs=2, split=(0.75, 0.125, 0.125),
               weight_decay=1e-2, context_jitter=0.5, patience=5,
               augment={"mix": 0.3, "gain": 0.3, "procedural": 0.3, "preset": "custom"})
    cfg.model.encoder.dropout = 0.1
    run = train(cfg)
    assert len(run.history) == 3
    assert all(math.isfinite(value) for epoch in run.history for value in epoch.values())
    assert run.config.augment.procedural == 0.3 and run.config.model.encoder.dropout == 0.1
    checkpoint = load_checkpoint(run.path / "last.pt")
    assert "weight_decay" in checkpoint["optimizer"]["param_groups"][0]  # AdamW's state
    assert checkpoint["optimizer"]["param_groups"][0]["weight_decay"] == 1e-2
    assert frenbrdf.Model.load(run.path).config.encoder.dropout == 0.1


def test_patience_stops_when_validation_stops_improving(toy_materials, tmp_path):
    # A learning rate too small to move a float32 weight: no epoch improves on the first.
    run = train(tiny("nbrdf", toy_materials, tmp_path / "run", epochs=10, lr=1e-30, patience=2))
    assert [entry["epoch"] for entry in run.history] == [-1, 0, 1, 2]


def test_a_plateau_halves_the_learning_rate_and_a_resume_keeps_it(toy_materials, tmp_path):
    # No epoch improves on the first (epoch 0 is the best): the rate halves at epochs 2 and 4.
    cfg = tiny("nbrdf", toy_materials, tmp_path / "run", epochs=5, lr=1e-30, lr_plateau=2)
    run = train(cfg)
    assert [entry["lr"] for entry in run.history[1:]] == pytest.approx([1e-30, 1e-30, 1e-30, 5e-31, 5e-31])
    cfg.epochs = 7
    resumed = train(cfg, resume=True)
    assert [entry["lr"] for entry in resumed.history[-2:]] == pytest.approx([2.5e-31, 2.5e-31])
    with pytest.raises(ValueError, match="lr_plateau"):
        tiny("nbrdf", toy_materials, tmp_path / "bad", lr_plateau=-1)


def test_resuming_a_run_that_patience_stopped_trains_no_further(toy_materials, tmp_path):
    # No epoch improves on the first: patience 2 stops the run after epoch 2 of 10.
    cfg = tiny("nbrdf", toy_materials, tmp_path / "run", epochs=10, lr=1e-30, patience=2)
    run = train(cfg)
    assert run.history[-1]["epoch"] == 2
    saved = {name: (run.path / name).read_bytes() for name in ("last.pt", "best.pt", "history.json")}
    resumed = train(cfg, resume=True)
    assert resumed.history[-1]["epoch"] == 2
    assert {name: (run.path / name).read_bytes() for name in saved} == saved
    cfg.patience = 4  # a longer patience: the run goes on
    assert train(cfg, resume=True).history[-1]["epoch"] == 4


def test_dropout_and_weight_decay_change_nothing_when_off(toy_materials, tmp_path):
    from frenbrdf.models.autoencoder import AutoEncoder
    from frenbrdf.training.loop import make_optimizer

    cfg = tiny("nbrdf", toy_materials, tmp_path / "run")
    plain = AutoEncoder(cfg.model)
    assert type(make_optimizer(plain, cfg)) is torch.optim.Adam
    cfg.model.encoder.dropout = 0.5
    dropped = AutoEncoder(cfg.model)
    assert set(dropped.state_dict()) != set(plain.state_dict())  # dropout layers shift the indices
    samples = torch.randn(2, 50, 9)
    dropped.train()
    assert not torch.equal(dropped.encoder(samples), dropped.encoder(samples))
    dropped.eval()
    assert torch.equal(dropped.encoder(samples), dropped.encoder(samples))


def test_configs_and_run_folders_from_before_augmentation_still_load(toy_materials, tmp_path):
    run = train(tiny("nbrdf", toy_materials, tmp_path / "run", epochs=1))
    saved = json.loads((run.path / "config.json").read_text())
    assert saved["augment"]["preset"] == "paper" and saved["holdout"] == []  # tiny runs train on the tables
    for key in ("augment", "holdout", "weight_decay", "context_jitter", "patience"):
        del saved[key]
    del saved["model"]["encoder"]["dropout"]
    (run.path / "config.json").write_text(json.dumps(saved))
    old = Run(run.path).config
    assert old.augment.preset == "paper" and not old.augment.active
    assert (old.holdout, old.weight_decay, old.context_jitter, old.patience, old.model.encoder.dropout) == ((), 0, 0, 0,
                                                                                                          0)
    assert frenbrdf.Model.load(run.path).config.encoder.dropout == 0.0
    augmented = config_for("hyperbrdf", augmentation="augmented")
    assert augmented.augment.mix == presets.AUGMENTATION["augmented"]["mix"] and augmented.lr == 5e-5


def test_validation_renders_are_logged_and_pick_the_best_checkpoint(toy_materials, tmp_path):
    cfg = tiny("nbrdf", toy_materials, tmp_path / "run", epochs=5, render_every=2, render_resolution=16,
               select="psnr")
    run = train(cfg)
    rendered = [entry["epoch"] for entry in run.history if "val_psnr" in entry]
    assert rendered == [1, 3, 4]  # every second epoch, and the last
    seconds = [entry["seconds"] for entry in run.history[1:]]
    assert all(0 < a < b for a, b in itertools.pairwise(seconds))
    # best.pt is the epoch of highest validation PSNR; the loss rule's pick is kept beside it.
    by_psnr = max((e for e in run.history if "val_psnr" in e), key=lambda e: e["val_psnr"])
    by_loss = min(run.history[1:], key=lambda e: e["val_rec"])
    assert run.best_epoch == by_psnr["epoch"] and run.best_by("loss")["epoch"] == by_loss["epoch"]
    assert load_checkpoint(run.path / "best.pt")["epoch"] == by_psnr["epoch"]
    assert load_checkpoint(run.path / "best-loss.pt")["epoch"] == by_loss["epoch"]
    # The logged PSNR is what scoring the best checkpoint on the validation files gives.
    from frenbrdf.render.scoring import reconstruction_rows

    files = [toy_materials / f"{name}.binary" for name in run.split.val]
    rows = reconstruction_rows(run.model(), files, resolution=16, seed=cfg.seed, frequency_metric=False,
                               progress=False)
    assert np.mean([r["psnr"] for r in rows]) == pytest.approx(by_psnr["val_psnr"], abs=1e-4)


def test_selection_by_render_psnr_needs_the_renders(toy_materials, tmp_path):
    with pytest.raises(ValueError, match="select 'psnr' needs render_every"):
        tiny("nbrdf", toy_materials, tmp_path / "run", select="psnr")
    with pytest.raises(ValueError, match="select must be one of"):
        tiny("nbrdf", toy_materials, tmp_path / "run", select="ssim")
    with pytest.raises(ValueError, match="patience"):
        tiny("nbrdf", toy_materials, tmp_path / "run", select="psnr", render_every=5, patience=2)


def test_cli_trains_selecting_by_validation_renders(toy_materials, tmp_path, capsys):
    out = tmp_path / "run"
    config_file = tmp_path / "tiny.json"
    config_file.write_text(json.dumps(to_dict(tiny("nbrdf", toy_materials, out, epochs=2, render_resolution=16))))
    assert cli.main(["train", "--config", str(config_file), "--render-every", "1", "--select", "psnr", "--quiet",
                     "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    run = Run(out)
    assert run.config.select == "psnr" and summary["selected_by"] == "psnr"
    assert summary["best_val_psnr"] == max(e["val_psnr"] for e in run.history if "val_psnr" in e)
