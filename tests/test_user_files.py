"""Issue 45: every field of every file a user can hand us is checked where it is read, special files are refused
by every reader before anything is written, and the CLI ends with one line that names the real problem."""

from __future__ import annotations

import json
import os
import re
import threading
from pathlib import Path

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf import cli
from frenbrdf.configs import to_dict
from frenbrdf.io.jsonfile import MAX_DEPTH, read_json
from frenbrdf.io.outputs import MARKER
from frenbrdf.models import pretrained
from frenbrdf.training import load_config, train

from .conftest import tiny


def _fails(argv, capsys) -> str:
    """Runs the CLI, which must exit with status 2 and one line ``frenbrdf CMD: error: …`` (no traceback)."""
    with pytest.raises(SystemExit) as exit_info:
        cli.main([str(arg) for arg in argv])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"frenbrdf {argv[0]}: error: "), err
    return last


@pytest.fixture(scope="module")
def run(toy_materials, tmp_path_factory):
    """A one-epoch run and the config file that made it."""
    folder = tmp_path_factory.mktemp("user-files")
    cfg = tiny("nbrdf", toy_materials, folder / "run", epochs=1)
    train(cfg)
    config = folder / "tiny.json"
    config.write_text(json.dumps(to_dict(cfg)))
    return folder / "run", config


# --------------------------------------------------------------------------- checkpoints


def _generator(c):
    c["generator"] = torch.zeros(3, dtype=torch.uint8)


def _history(c):
    c["history"] = {"epoch": 0}


def _history_entry(c):
    c["history"].append("epoch 1")


def _no_optimizer(c):
    del c["optimizer"]


def _optimizer_state(c):
    c["optimizer"]["state"][0]["exp_avg"] = torch.zeros(2)


def _optimizer_lr(c):
    c["optimizer"]["param_groups"][0]["lr"] = "fast"


def _weights(c):
    c["model"].popitem()


def _epoch(c):
    c["epoch"] = "0"


def _best(c):
    c["best"] = None


def _split(c):
    c["split"] = {"train": 3}


def _config(c):
    c["config"] = "{"


DAMAGES = {
    "generator": (_generator, "generator: not the state of a torch CPU random generator"),
    "history": (_history, "history must be a list of epochs"),
    "history-entry": (_history_entry, r"history\[2\] must be an epoch's record"),
    "no-optimizer": (_no_optimizer, "it lacks optimizer"),
    "optimizer-state": (_optimizer_state, r"optimizer: exp_avg of parameter 0 must be finite numbers of shape"),
    "optimizer-lr": (_optimizer_lr, "optimizer: parameter group 0: lr must be a finite number"),
    "weights": (_weights, r"model \(the weights\) does not fit the run's model config"),
    "epoch": (_epoch, "epoch must be an integer ≥ 0"),
    "best": (_best, "best must be"),
    "split": (_split, "split: train must be a list of material names"),
    "config": (_config, "config: not valid JSON: .* at line 1, column 2"),
}


@pytest.mark.parametrize("damage", sorted(DAMAGES))
def test_a_damaged_last_pt_is_named_before_the_run_folder_is_touched(damage, run, tmp_path, capsys):
    source, config = run
    folder = tmp_path / "run"
    folder.mkdir()
    for path in source.iterdir():
        (folder / path.name).write_bytes(path.read_bytes())
    change, message = DAMAGES[damage]
    checkpoint = torch.load(folder / "last.pt", weights_only=True)
    change(checkpoint)
    torch.save(checkpoint, folder / "last.pt")
    before = {path.name: (path.read_bytes(), path.stat().st_mtime_ns) for path in folder.iterdir()}
    saved = json.loads(config.read_text())
    config = tmp_path / "tiny.json"
    config.write_text(json.dumps({**saved, "out": str(folder)}))

    line = _fails(["train", "--config", config, "--epochs", 2, "--resume", "--quiet"], capsys)
    assert str(folder / "last.pt") in line
    assert re.search(message, line), line
    after = {path.name: (path.read_bytes(), path.stat().st_mtime_ns) for path in folder.iterdir()}
    assert after == before  # config.json, split.json, mapping.npz, … untouched


def test_a_good_last_pt_still_resumes(run, tmp_path):
    source, config = run
    folder = tmp_path / "run"
    folder.mkdir()
    for path in source.iterdir():
        (folder / path.name).write_bytes(path.read_bytes())
    cfg = load_config(config, out=str(folder), epochs=2)
    assert [entry["epoch"] for entry in train(cfg, resume=True).history] == [-1, 0, 1]


def test_a_resume_refuses_run_files_that_frenbrdf_train_did_not_write(run, tmp_path, capsys):
    """A folder holding a last.pt and a run's files but no marker of train's: resuming would replace files no run
    of train wrote (a user's config.json), so it is refused and nothing changes."""
    source, config = run
    folder = tmp_path / "copied"
    folder.mkdir()
    for path in source.iterdir():
        if path.name != MARKER:
            (folder / path.name).write_bytes(path.read_bytes())
    before = {path.name: path.read_bytes() for path in folder.iterdir()}
    last = _fails(["train", "--config", config, "--out", folder, "--resume", "--quiet"], capsys)
    assert "which this command would replace and did not write" in last, last
    assert {path.name: path.read_bytes() for path in folder.iterdir()} == before


def _copy_run(source: Path, folder: Path) -> Path:
    folder.mkdir()
    for name in ("best.pt", "mapping.npz", "config.json"):
        (folder / name).write_bytes((source / name).read_bytes())
    return folder


@pytest.mark.parametrize(("field", "value", "message"), [
    ("reference", np.zeros((3, 4)), r"reference \(f_ref\) must be numbers of shape \(3,\)"),
    ("reference", np.array([1.0, np.nan, 1.0]), r"reference \(f_ref\) must be finite and ≥ 0"),
    ("epsilon", np.zeros(2), "epsilon must be one number"),
    ("offset", np.float64(0.5), "offset .* must be 0 or 1"),
    ("epsilon", None, "not a frenbrdf mapping: it lacks epsilon"),
])
def test_a_damaged_mapping_file_names_the_file_and_the_field(field, value, message, run, tmp_path):
    folder = _copy_run(run[0], tmp_path / "run")
    saved = dict(np.load(folder / "mapping.npz"))
    if value is None:
        del saved[field]
    else:
        saved[field] = value
    np.savez(folder / "mapping.npz", **saved)
    with pytest.raises(ValueError, match=f"mapping.npz: {message}"):
        frenbrdf.Model.load(folder)


def test_a_damaged_packed_model_names_the_file_and_the_field(tmp_path):
    folder = tmp_path / "packed"
    folder.mkdir()
    for name in (pretrained.MODEL_FILE, pretrained.MAPPING_FILE, pretrained.CARD_FILE):
        (folder / name).write_bytes((pretrained.PACKAGE_DIR / name).read_bytes())
    assert frenbrdf.Model.pretrained(folder).card
    saved = dict(np.load(folder / pretrained.MAPPING_FILE))
    np.savez(folder / pretrained.MAPPING_FILE, **{**saved, "epsilon": np.array("x")})
    with pytest.raises(ValueError, match="mapping.npz: epsilon must be one number"):
        frenbrdf.Model.pretrained(folder)
    np.savez(folder / pretrained.MAPPING_FILE, **saved)
    (folder / pretrained.CARD_FILE).write_text("[1, 2")
    with pytest.raises(ValueError, match="card.json: not valid JSON: .* line 1, column 6"):
        frenbrdf.Model.pretrained(folder)
    (folder / pretrained.CARD_FILE).unlink()
    os.mkfifo(folder / pretrained.CARD_FILE)
    with pytest.raises(ValueError, match="card.json: a FIFO"):
        frenbrdf.Model.pretrained(folder)


# --------------------------------------------------------------------------- JSON files


class _Unblocked:
    """A FIFO that a reader opening it gets EOF from at once, so that a test fails instead of hanging; ``read``
    says whether anyone opened it to read (the code under test must not)."""

    def __init__(self, fifo: Path):
        self.fifo, self.read, self.closing = fifo, False, False
        self.thread = threading.Thread(target=self._write, daemon=True)

    def _write(self):
        os.close(os.open(self.fifo, os.O_WRONLY))  # blocks until someone opens it to read; EOF for them
        self.read = not self.closing

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.closing = True
        os.close(os.open(self.fifo, os.O_RDONLY | os.O_NONBLOCK))  # releases the writer if nobody read
        self.thread.join(5)


def test_fifos_named_as_config_or_front_are_refused_not_waited_on(toy_materials, tmp_path, capsys):
    fifo = tmp_path / "config.json"
    os.mkfifo(fifo)
    for argv in (["train", "--config", fifo, "--data", toy_materials, "--out", tmp_path / "run", "--quiet"],
                 ["select", "--data", toy_materials, "--target-psnr", 30, "--out", tmp_path / "s", "--config", fifo],
                 ["select", "--data", toy_materials, "--target-psnr", 30, "--out", tmp_path / "s", "--front", fifo]):
        with _Unblocked(fifo) as unblocked:
            assert "config.json: a FIFO (named pipe)" in _fails(argv, capsys)
        assert not unblocked.read
    assert not (tmp_path / "run").exists() and not (tmp_path / "s").exists()


@pytest.mark.parametrize(("text", "message"), [
    ('{"x": ' * 5000 + "1" + "}" * 5000, "nest too deeply"),
    ("[" * 100_000 + "]" * 100_000, "nest too deeply"),
    ('{"model": ' * (MAX_DEPTH + 5) + "{}" + "}" * (MAX_DEPTH + 5), f"nest {MAX_DEPTH + 6} levels deep"),
    ('{"epochs": 2,\n "lr": }', "not valid JSON: Expecting value at line 2, column 8"),
    ('{"epochs": ' + "9" * 5000 + "}", "an integer of more than 4300 digits"),
    ("[]", "must be a JSON object, got a JSON list"),
    (b"\xff\xfe{}", "not UTF-8 text"),
    ('{"lr": NaN}', r"lr must lie in \(0, 1\], got nan"),
    ('{"split": [0.5, 0.5, 0.5]}', "split must be three fractions in \\[0, 1\\] summing to 1"),
    ('{"seed": 18446744073709551616}', "seed must lie in 0 … 4294967295"),
    ('{"augment": {"mix": Infinity}}', r"mix must lie in \[0, 1\]"),
])
def test_a_config_file_is_read_checked_and_named(text, message, toy_materials, tmp_path, capsys):
    config = tmp_path / "config.json"
    config.write_bytes(text if isinstance(text, bytes) else text.encode())
    line = _fails(["train", "--config", config, "--data", toy_materials, "--out", tmp_path / "run", "--quiet"],
                  capsys)
    assert f"{config}: " in line and re.search(message, line), line
    assert not (tmp_path / "run").exists()


def test_read_json_refuses_oversize_files_and_checks_the_top_level_type(tmp_path):
    path = tmp_path / "history.json"
    path.write_text(json.dumps([{"epoch": 0}] * 10))
    assert read_json(path, expect=list) == [{"epoch": 0}] * 10
    with pytest.raises(ValueError, match="larger than the 16 bytes a history may have"):
        read_json(path, "history", expect=list, max_bytes=16)
    with pytest.raises(ValueError, match="a history must be a JSON object, got a JSON list"):
        read_json(path, "history")


def test_damaged_run_folder_records_are_named(run, tmp_path):
    folder = _copy_run(run[0], tmp_path / "run")
    (folder / "history.json").write_text('[{"epoch": "one"}]')
    (folder / "split.json").write_text('{"train": "abc", "val": [], "test": [], "seed": 0}')
    opened = frenbrdf.training.Run(folder)
    with pytest.raises(ValueError, match="history.json: not a training history"):
        _ = opened.history
    with pytest.raises(ValueError, match="split.json: train must be a list of material names"):
        _ = opened.split


# --------------------------------------------------------------------------- options


@pytest.mark.parametrize(("argv", "message"), [
    (["train", "--seed", str(2**64)], "argument --seed: a seed is a whole number in 0 … 4,294,967,295"),
    (["train", "--seeds", "1", "-2"], "argument --seeds: a seed is a whole number in 0 … 4,294,967,295"),
    (["synth", "OUT", "--seed", "²"], "argument --seed: a seed is a whole number"),
    (["train", "--epochs", "0"], "argument --epochs: expected a whole number in 1 … 1,000,000, got '0'"),
    (["train", "--render-every", "-1"], "argument --render-every: expected a whole number in 0 … 1,000,000"),
    (["synth", "OUT", "--n", "0"], "argument --n: expected a whole number in 1 … 10,000"),
    (["evaluate", "RUN", "--out", "E", "--edits", "-1"], "argument --edits: expected a whole number in 0 …"),
    (["evaluate", "RUN", "--out", "E", "--max-materials", "-1"], "argument --max-materials: expected"),
    (["evaluate", "RUN", "--out", "E", "--samples", "0"], "argument --samples: expected a whole number in 1 … 1,458"),
    (["evaluate", "RUN", "--out", "E", "--resolution", "7"], "argument --resolution: expected a whole number in 8 …"),
    (["render", "M", "--out", "x.png", "--resolution", "99999"], "argument --resolution: expected"),
    (["render", "M", "--out", "x.png", "--mitsuba", "--spp", "0"], "argument --spp: expected a whole number in 1 …"),
    (["reconstruct", "M", "--out", "R", "--width", "0"], "argument --width: expected a whole number in 1 … 1,024"),
    (["spectrum", "M", "--out", "S", "--lmax", "0"], "argument --lmax: expected a whole number in 1 … 511"),
    (["fit-nbrdf", "M", "--out", "F", "--epochs", "1e3"], "argument --epochs: expected a whole number"),
    (["demo", "--epochs", "-3"], "argument --epochs: expected a whole number in 1 …"),
    (["select", "--data", "D", "--out", "S", "--target-psnr", "nan"], "argument --target-psnr: expected a finite"),
    (["select", "--data", "D", "--out", "S", "--target-psnr", "inf"], "argument --target-psnr: expected a finite"),
])
def test_integer_and_decibel_options_say_their_range(argv, message, capsys):
    assert message in _fails(argv, capsys)


def test_ctrl_c_ends_with_one_line_and_status_130(monkeypatch, capsys):
    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli.commands, "info", interrupted)  # build_parser binds the command functions when called
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["info"])
    assert exit_info.value.code == 130
    assert capsys.readouterr().err == "frenbrdf info: interrupted\n"


def test_the_resume_check_allocates_nothing_and_draws_no_random_numbers(run):
    from frenbrdf.training.loop import checked_resume

    state = torch.get_rng_state()
    source, config = run
    assert checked_resume(source, load_config(config))["epoch"] == 0
    assert torch.equal(state, torch.get_rng_state())  # the network it checks against is built on the meta device


def test_a_fifo_in_the_truth_cache_is_replaced_not_read(tmp_path, merl_table):
    from frenbrdf.models.losses import FrequencyLossConfig, FrequencyTruth

    truth = FrequencyTruth(FrequencyLossConfig(lmax=7, slices=(0, 30)), tmp_path)
    mapped = np.log(np.maximum(merl_table.reshape(3, -1).T, 0) + 0.01)
    valid = np.all(merl_table.reshape(3, -1) >= 0, axis=0)
    os.mkfifo(tmp_path / "key.npy")
    with _Unblocked(tmp_path / "key.npy") as unblocked:
        computed = truth.coefficients(mapped, valid, "key")
    assert not unblocked.read
    np.testing.assert_array_equal(np.load(tmp_path / "key.npy"), computed)


def test_a_resume_with_another_method_or_model_names_the_difference_not_a_weight(run, tmp_path, capsys):
    source, config = run
    folder = tmp_path / "run"
    folder.mkdir()
    for path in source.iterdir():
        (folder / path.name).write_bytes(path.read_bytes())
    before = {path.name: path.read_bytes() for path in folder.iterdir()}
    last = _fails(["train", "--config", config, "--method", "frenbrdf", "--out", folder, "--resume", "--quiet"], capsys)
    assert "the run was trained with another method ('nbrdf', this resume asks for 'frenbrdf')" in last, last
    other = to_dict(load_config(config))
    other["model"]["nbrdf"]["hidden"] = [h + 1 for h in other["model"]["nbrdf"]["hidden"]]
    (tmp_path / "other.json").write_text(json.dumps(other))
    last = _fails(["train", "--config", tmp_path / "other.json", "--out", folder, "--resume", "--quiet"], capsys)
    assert re.search(r"another model\.\w+\.hidden \(", last), last
    assert {path.name: path.read_bytes() for path in folder.iterdir()} == before


def test_evaluate_never_writes_into_its_data_folder_and_train_refuses_a_repeated_seed(run, capsys):
    source, config = run
    data = load_config(config).data
    before = sorted(p.name for p in Path(data).iterdir())
    last = _fails(["evaluate", source, "--data", data, "--out", data, "--overwrite", "--quiet"], capsys)
    assert f"is the input {data}" in last, last
    assert sorted(p.name for p in Path(data).iterdir()) == before
    last = _fails(["train", "--config", config, "--seeds", 0, 1, 0, "--out", Path(source).parent / "seeds"], capsys)
    assert "--seeds repeats a seed (0 1 0)" in last, last
