"""Issue 30: nothing a user has is lost, nothing crashes, nothing lies — one test per defect found by fuzzing.

docs/stability.md ("Inputs, outputs and a user's files") lists what these show.
"""

from __future__ import annotations

import json
import os
import stat

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf import cli
from frenbrdf.io import read_material, read_samples, write_material
from frenbrdf.io.nbrdf import read_nbrdf
from frenbrdf.io.outputs import MARKER

from .conftest import tiny
from .test_measurements import VECTORS, samples, write_csv


def _cli(*args) -> tuple[int, str]:
    """Runs the CLI; (exit code, stderr-free message) — 0 or the code of parser.exit."""
    try:
        return cli.main([str(a) for a in args]), ""
    except SystemExit as exit_info:
        return exit_info.code, ""


@pytest.fixture(scope="module")
def run_dir(toy_materials, tmp_path_factory):
    from frenbrdf.training import train

    return train(tiny("frenbrdf", toy_materials, tmp_path_factory.mktemp("inputs") / "run", epochs=1)).path


@pytest.fixture(scope="module")
def model(run_dir):
    return frenbrdf.Model.load(run_dir)


@pytest.fixture()
def csv_input(tmp_path):
    return write_csv(tmp_path / "measured.csv", samples(80))


# --------------------------------------------------------------------------- 1–4: a user's files


def _reconstruct(source, out, run_dir, *extra):
    return _cli("reconstruct", source, "--out", out, "--model", run_dir, "--refine", "none", "--quiet", *extra)[0]


def test_reconstruct_never_touches_a_folder_it_did_not_write(run_dir, csv_input, tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "truth.png").write_bytes(b"the user's own")
    (mine / "render.png").write_bytes(b"the user's own too")
    assert _reconstruct(csv_input, mine, run_dir) == 2
    assert "holds render.png, truth.png (not this command's earlier output)" in capsys.readouterr().err
    assert (mine / "truth.png").read_bytes() == b"the user's own" and len(list(mine.iterdir())) == 2
    # --out equal to the input's folder, or holding it, is refused even with --overwrite.
    for out in (csv_input.parent, tmp_path.parent):
        assert _reconstruct(csv_input, out, run_dir, "--overwrite") == 2
        assert "its folder, or holds it" in capsys.readouterr().err
    # A result folder of this command with a file of the user's beside it: the message names that file.
    assert _reconstruct(csv_input, tmp_path / "result", run_dir) == 0
    (tmp_path / "result" / "notes.txt").write_text("mine")
    assert _reconstruct(csv_input, tmp_path / "result", run_dir) == 2
    assert "holds notes.txt (not this command's earlier output)" in capsys.readouterr().err
    assert _reconstruct(csv_input, "", run_dir) == 2
    assert "--out is empty" in capsys.readouterr().err
    assert csv_input.exists()
    # --overwrite writes beside the user's files, never over one: a file at a name it writes is refused.
    assert _reconstruct(csv_input, mine, run_dir, "--overwrite") == 2
    assert "holds render.png, truth.png, which this command would replace" in capsys.readouterr().err
    (mine / "render.png").unlink()
    (mine / "truth.png").rename(mine / "my-truth.png")
    assert _reconstruct(csv_input, mine, run_dir, "--overwrite") == 0
    assert (mine / "my-truth.png").read_bytes() == b"the user's own" and (mine / "reconstruction.json").exists()


def test_reconstruct_replaces_its_own_earlier_folder_whole(run_dir, toy_materials, csv_input, tmp_path):
    out = tmp_path / "result"
    source = sorted(toy_materials.glob("*.binary"))[0]
    assert _reconstruct(source, out, run_dir, "--samples", 300) == 0
    assert (out / "truth.png").exists()
    assert _reconstruct(csv_input, out, run_dir) == 0  # an earlier result: replaced whole, nothing stale left
    assert sorted(p.name for p in out.iterdir() if p.name != MARKER) == json.loads(
        (out / "reconstruction.json").read_text())["files"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_train_never_replaces_a_run_without_being_asked(toy_materials, tmp_path, capsys):
    from frenbrdf.training.loop import check_run_folder

    cfg = tiny("frenbrdf", toy_materials, tmp_path / "run", epochs=1)
    config = tmp_path / "cfg.json"
    config.write_text(json.dumps({"data": str(toy_materials), "epochs": 1, "context_samples": 64,
                                  "query_samples": 64, "batch_materials": 2, "cache_dir": str(tmp_path / "cache"),
                                  "model": {"nbrdf": {"hidden": [8]}, "encoder": {"hidden": [8], "latent": 4},
                                            "decoder": {"hidden": [8]}},
                                  "loss": {"eta": 0.0}}))
    run = tmp_path / "run"
    assert _cli("train", "--config", config, "--out", run, "--quiet")[0] == 0
    before = (run / "best.pt").read_bytes()
    assert _cli("train", "--config", config, "--out", run, "--quiet")[0] == 2
    assert "already holds a training run" in capsys.readouterr().err
    assert (run / "best.pt").read_bytes() == before
    with pytest.raises(ValueError, match="already holds"):
        check_run_folder(cfg)
    (run / "best-psnr.pt").write_bytes(b"an earlier run's")  # as if the earlier run had written it
    marker = json.loads((run / MARKER).read_text())
    (run / MARKER).write_text(json.dumps({**marker, "entries": [*marker["entries"], "best-psnr.pt"]}))
    assert _cli("train", "--config", config, "--out", run, "--quiet", "--overwrite")[0] == 0
    assert not (run / "best-psnr.pt").exists()  # nothing of the earlier run passes for this one's
    other = tmp_path / "theirs"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="holds notes.txt"):
        check_run_folder(tiny("frenbrdf", toy_materials, other))
    with pytest.raises(ValueError, match="its folder, or holds it"):
        check_run_folder(tiny("frenbrdf", toy_materials, toy_materials), overwrite=True)


def test_evaluate_checks_everything_before_computing(toy_materials, tmp_path, capsys):
    from frenbrdf.training import train

    runs = [train(tiny(method, toy_materials, tmp_path / f"{method}-{seed}", epochs=1, seed=seed)).path
            for method, seed in (("frenbrdf", 0), ("nbrdf", 0), ("frenbrdf", 1))]
    out = tmp_path / "E"
    assert _cli("evaluate", *runs, "--out", out, "--quiet")[0] == 2
    assert "every seed needs runs of the same methods" in capsys.readouterr().err
    assert not out.exists()  # nothing written: not E/seed-0 first
    file = tmp_path / "file.txt"
    file.write_text("x")
    assert _cli("evaluate", runs[0], "--out", file, "--quiet")[0] == 2
    assert "exists and is not a folder" in capsys.readouterr().err
    assert _cli("evaluate", runs[0], "--out", runs[0], "--quiet")[0] == 2  # a run folder is not an output folder
    assert "is the input" in capsys.readouterr().err


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_an_unwritable_out_fails_first(run_dir, tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        assert _cli("evaluate", run_dir, "--out", locked / "E", "--quiet")[0] == 2
        assert "cannot write" in capsys.readouterr().err
    finally:
        locked.chmod(0o700)


# --------------------------------------------------------------------------- 5–9: named errors, not crashes


def test_sizes_from_a_config_have_limits_that_name_the_setting(tmp_path):
    from frenbrdf.training import load_config

    for setting, pattern in (({"loss": {"frequency": {"lmax": 100000}}}, "lmax must lie in 1 … 511"),
                             ({"model": {"nbrdf": {"hidden": [20000]}}}, "nbrdf.hidden"),
                             ({"model": {"encoder": {"latent": 10**9}}}, "encoder sizes"),
                             ({"context_samples": 10**9}, "context_samples must be ≤"),
                             ({"model": {"decoder": {"hidden": [4096, 4096]}, "nbrdf": {"hidden": [1024, 1024]}}},
                              "parameters, more than")):
        path = tmp_path / "cfg.json"
        path.write_text(json.dumps(setting))
        with pytest.raises(ValueError, match=pattern):
            load_config(path)


def test_sht_plans_refuse_sizes_before_allocating():
    from frenbrdf.numerics.sht import SHT

    with pytest.raises(ValueError, match="lmax"):
        SHT(100001, 200002, 100000)


def _checkpoint(run_dir, tmp_path, name, change):
    checkpoint = torch.load(run_dir / "best.pt", weights_only=True)
    change(checkpoint)
    folder = tmp_path / name
    folder.mkdir()
    torch.save(checkpoint, folder / "best.pt")
    (folder / "mapping.npz").write_bytes((run_dir / "mapping.npz").read_bytes())
    return folder


def test_damaged_run_folders_are_named(run_dir, tmp_path):
    def config(change):
        def apply(checkpoint):
            saved = json.loads(checkpoint["config"])
            checkpoint["config"] = json.dumps(change(saved))
        return apply

    cases = {
        "no-model": (config(lambda c: {k: v for k, v in c.items() if k != "model"}), "no model settings"),
        "list": (config(lambda c: [c]), "no model settings"),
        "shapes": (config(lambda c: {**c, "model": {**c["model"], "nbrdf": {"hidden": [17, 16]}}}),
                   "do not match its model config"),
        "huge": (config(lambda c: {**c, "model": {**c["model"], "nbrdf": {"hidden": [1024, 1024]},
                                                  "decoder": {"hidden": [4096]}}}), "parameters, more than"),
        "types": (config(lambda c: {**c, "model": {**c["model"], "nbrdf": {"hidden": "big"}}}), "must be a list"),
        "nan": (_poison_first_weight, "hold NaN or inf"),
        "no-method": (lambda c: c.pop("method"), "not a complete frenbrdf model"),
    }
    for name, (change, message) in cases.items():
        folder = _checkpoint(run_dir, tmp_path, name, change)
        with pytest.raises(ValueError, match=message) as error:
            frenbrdf.Model.load(folder)
        assert str(folder / "best.pt") in str(error.value)


def _poison_first_weight(checkpoint):
    name = next(iter(checkpoint["model"]))
    checkpoint["model"][name] = checkpoint["model"][name] * np.nan


def load_nbrdf(path):
    """A saved NBRDF as its network: read, then checked whole."""
    return frenbrdf.NBRDF.from_weights(read_material(path))


def _saved_nbrdf(tmp_path, params, epsilon=0.002, name="m.pt", **extra):
    path = tmp_path / name
    torch.save({"params": params, "reference": torch.zeros(3), "epsilon": epsilon, "offset": 0.0, **extra}, path)
    return path


def test_a_saved_nbrdfs_order_flag_must_be_a_bool(tmp_path):
    good = [torch.zeros(8, 6), torch.zeros(8), torch.zeros(3, 8), torch.zeros(3)]
    assert not load_nbrdf(_saved_nbrdf(tmp_path, good)).ordered  # files from before ordered NBRDFs
    assert load_nbrdf(_saved_nbrdf(tmp_path, good, ordered=True)).ordered
    with pytest.raises(ValueError, match="m.pt: not a valid saved NBRDF: its 'ordered' flag is a str"):
        load_nbrdf(_saved_nbrdf(tmp_path, good, ordered="yes"))


def test_saved_nbrdfs_of_wrong_shapes_or_widths_are_named(tmp_path, capsys):
    good = [torch.zeros(8, 6), torch.zeros(8), torch.zeros(3, 8), torch.zeros(3)]
    assert len(load_nbrdf(_saved_nbrdf(tmp_path, good))) == 1
    for params, message in (([torch.zeros(8, 5), torch.zeros(8), torch.zeros(3, 8), torch.zeros(3)], "layer 1"),
                            ([torch.zeros(8, 6), torch.zeros(8), torch.zeros(4, 8), torch.zeros(4)], "layer 2"),
                            ([torch.zeros(8, 6)], "pairs"),
                            ([torch.zeros(20000, 6), torch.zeros(20000), torch.zeros(3, 20000), torch.zeros(3)],
                             "20000 wide"),
                            ([torch.zeros(8, 6), torch.zeros(8), torch.zeros(3, 8), torch.full((3,), np.nan)], "NaN")):
        path = _saved_nbrdf(tmp_path, params)
        with pytest.raises(ValueError, match=message):
            load_nbrdf(path)
        assert _cli("render", path, "--out", tmp_path / "x.png", "--resolution", 16)[0] == 2
        assert "m.pt: not a valid saved NBRDF" in capsys.readouterr().err


def test_a_wide_keras_file_is_refused_before_it_is_evaluated(tmp_path):
    from frenbrdf.io.keras import read_keras_nbrdf

    from .conftest import write_keras_h5

    path = write_keras_h5(tmp_path / "wide.h5", [(np.zeros((6, 20000)), np.zeros(20000)),
                                                 (np.zeros((20000, 3)), np.zeros(3))])
    with pytest.raises(ValueError, match="wide.h5: .*20000"):
        read_keras_nbrdf(path)


def test_train_config_types_are_named(tmp_path):
    from frenbrdf.training import load_config

    for setting, message in (({"epochs": None}, "epochs must be an integer, got None"),
                             ({"epochs": "1"}, "epochs must be an integer, got '1'"),
                             ({"epochs": 1.5}, "epochs must be an integer"),
                             ({"lr": "0.001"}, "lr must be a number"),
                             ({"seed": "abc"}, "seed must be an integer"),
                             ({"progress": 1}, "progress must be true or false"),
                             ({"model": {"nbrdf": {"hidden": 8}}}, "hidden must be a list, got 8"),
                             ({"model": {"nbrdf": {"hidden": "big"}}}, "hidden must be a list, got 'big'"),
                             ({"lr": 1e30}, r"lr must lie in \(0, 1\]")):
        path = tmp_path / "cfg.json"
        path.write_text(json.dumps(setting))
        with pytest.raises(ValueError, match=message):
            load_config(path)


def test_training_diverged_is_a_clean_exit(monkeypatch, toy_materials, tmp_path, capsys):
    import frenbrdf.training as training
    from frenbrdf.exceptions import TrainingDiverged

    def diverging(cfg, **_):
        raise TrainingDiverged("step 3: loss term(s) ['rec'] became NaN/inf")

    monkeypatch.setattr(training, "train", diverging)
    assert _cli("train", "--data", toy_materials, "--out", tmp_path / "run", "--quiet")[0] == 2
    assert "error: step 3" in capsys.readouterr().err


def test_a_poisoned_truth_cache_entry_is_recomputed(tmp_path, merl_table):
    from frenbrdf.models.losses import FrequencyLossConfig, FrequencyTruth

    truth = FrequencyTruth(FrequencyLossConfig(lmax=7, slices=(0, 30)), tmp_path)
    mapped = np.log(np.maximum(merl_table.reshape(3, -1).T, 0) + 0.01)
    valid = np.all(merl_table.reshape(3, -1) >= 0, axis=0)
    clean = truth.coefficients(mapped, valid, "key")
    poisoned = clean.copy()
    poisoned[0, 0, 0] = np.nan
    np.save(tmp_path / "key.npy", poisoned)
    np.testing.assert_array_equal(truth.coefficients(mapped, valid, "key"), clean)
    assert np.all(np.isfinite(np.load(tmp_path / "key.npy")))


def test_render_out_is_checked_before_rendering(tmp_path, toy_materials, capsys):
    source = sorted(toy_materials.glob("*.binary"))[0]
    for out, message in ((f"{tmp_path}/", "is a folder"), (tmp_path / "x", "must end in .png"),
                         (tmp_path / "x.jpg", "must end in .png")):
        assert _cli("render", source, "--out", out, "--resolution", 16)[0] == 2
        assert message in capsys.readouterr().err
    assert _cli("render", tmp_path / "absent.binary", "--out", tmp_path / "x.png")[0] == 2
    assert "does not exist" in capsys.readouterr().err


def test_a_csv_with_a_huge_field_is_named(tmp_path):
    path = tmp_path / "huge.csv"
    path.write_text(",".join(VECTORS) + "\n" + "1" * 200_000 + ",0,1,0,0,1,1,1,1\n")
    with pytest.raises(ValueError, match=r"huge.csv: row 2: not readable as CSV"):
        read_samples(path)


# --------------------------------------------------------------------------- 10–12: time and memory


def test_csv_memory_stays_near_the_data_size(tmp_path):
    import tracemalloc

    rows = np.tile(samples(100), (2000, 1))  # 200,000 samples: 14.4 MB of float64
    path = tmp_path / "big.csv"
    np.savetxt(path, rows, delimiter=",", header=",".join(VECTORS), comments="")
    tracemalloc.start()
    try:
        measured = read_samples(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(measured) == 200_000
    assert peak < 5 * rows.nbytes, f"peak {peak / 1e6:.0f} MB for {rows.nbytes / 1e6:.0f} MB of data"


def test_an_npz_zip_bomb_is_refused_from_its_declared_sizes(tmp_path, monkeypatch):
    from frenbrdf.io import samples as sample_files

    monkeypatch.setattr(sample_files, "MAX_SAMPLES", 1000)
    path = tmp_path / "bomb.npz"
    np.savez_compressed(path, **{name: np.zeros(100_000) for name in sample_files.FORMS["vectors"]})
    assert path.stat().st_size < 20_000
    with pytest.raises(ValueError, match="bomb.npz: .*declares 800,128 bytes uncompressed"):
        read_samples(path)


def test_counts_are_capped_at_what_the_data_hold(toy_materials):
    source = sorted(toy_materials.glob("*.binary"))[0]
    every = read_samples(source, samples=None)
    assert len(read_samples(source, samples=10**9)) == len(every)  # not a billion draws


def test_what_is_not_a_regular_file_is_refused_by_every_reader(tmp_path):
    fifo = tmp_path / "pipe.binary"
    os.mkfifo(fifo)
    loop = tmp_path / "loop.csv"
    loop.symlink_to(loop)
    for reader in (read_samples, read_material, frenbrdf.read_merl, read_nbrdf, frenbrdf.read_bsdf):
        with pytest.raises(ValueError, match="pipe.binary: a FIFO"):
            reader(fifo)
        with pytest.raises(IsADirectoryError, match="got a folder"):
            reader(tmp_path)
    with pytest.raises(ValueError, match="a loop of symbolic links"):
        read_samples(loop)
    assert stat.S_ISFIFO(fifo.stat().st_mode)


def test_options_out_of_range_are_named(merl_file, tmp_path, capsys):
    from frenbrdf import cli

    for argv, message in ((["reconstruct", str(merl_file), "--out", str(tmp_path / "r"), "--seed", "-1"],
                           "argument --seed: a seed is a whole number in 0 … 4,294,967,295, got '-1'"),
                          (["convert", str(merl_file), str(tmp_path / "s.csv"), "--samples", "10"],
                           "argument --samples: expected a number ≥ 50")):
        with pytest.raises(SystemExit):
            cli.main(argv)
        assert message in capsys.readouterr().err
    # A folder that does not exist yet is made for the output.
    assert cli.main(["convert", str(merl_file), str(tmp_path / "new" / "s.csv"), "--samples", "60"]) == 0
    # An option where it does not apply is named, not ignored.
    samples_csv = tmp_path / "new" / "s.csv"
    for argv, message in ((["reconstruct", str(samples_csv), "--out", str(tmp_path / "r"), "--samples", "100"],
                           "--samples picks samples from a MERL file or a .bsdf"),
                          (["convert", str(merl_file), str(tmp_path / "t.binary"), "--samples", "100"],
                           "a .binary output is the whole table"),
                          (["render", str(merl_file), "--out", str(tmp_path / "x.png"), "--spp", "4"],
                           "--spp sets a --mitsuba render's samples per pixel")):
        with pytest.raises(SystemExit):
            cli.main(argv)
        assert message in capsys.readouterr().err
    assert not (tmp_path / "r").exists() and not (tmp_path / "t.binary").exists()


def test_a_link_loop_anywhere_on_the_command_line_is_an_error_not_a_traceback(tmp_path, merl_file, capsys):
    from frenbrdf import cli

    for name in ("lo", "lo.png"):
        (tmp_path / name).symlink_to(tmp_path / name)
    for argv in (["reconstruct", str(merl_file), "--out", str(tmp_path / "lo"), "--refine", "none", "--quiet"],
                 ["render", str(merl_file), "--out", str(tmp_path / "lo.png"), "--resolution", "16"],
                 ["train", "--data", str(tmp_path / "lo"), "--out", str(tmp_path / "run")]):
        with pytest.raises(SystemExit) as exit_:
            cli.main(argv)
        message = capsys.readouterr().err
        assert exit_.value.code == 2 and ("Symlink loop" in message or "loop of symbolic links" in message), message


# --------------------------------------------------------------------------- 13–15: no silent wrong answers


def test_reconstruct_checks_directions_like_the_files_are_checked(model):
    rows = samples(80)
    values, wi, wo = rows[:, 6:], rows[:, :3], rows[:, 3:6]
    with pytest.raises(ValueError, match="above the surface"):
        model.reconstruct(values, (wi * [1, 1, -1], wo), refine="none")
    with pytest.raises(ValueError, match="unit vectors"):
        model.reconstruct(values, (wi * 2, wo), refine="none")
    with pytest.raises(ValueError, match="unit vectors"):
        model.encode(values, (wi, wo * 0.5))


def test_what_would_produce_inf_is_refused(model, tmp_path):
    from frenbrdf.models.reconstruct import RefineConfig

    rows = samples(80)
    with pytest.raises(ValueError, match="values must be ≤"):
        model.reconstruct(rows[:, 6:] * 1e30, (rows[:, :3], rows[:, 3:6]))
    with pytest.raises(ValueError, match=r"weight_lr must lie in \(0, 1\]"):
        RefineConfig(weight_steps=10, weight_lr=1e6)
    with pytest.raises(ValueError, match="NaN or inf|not finite"):
        nbrdf = model.decode(np.full(model.config.encoder.latent, 1e30))
        nbrdf.merl_table()


def test_a_mapping_with_epsilon_at_or_below_zero_is_refused(tmp_path, run_dir):
    from frenbrdf.models.mapping import LogRelativeMapping

    for epsilon in (0.0, -0.002, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="ε must be a positive number"):
            LogRelativeMapping(np.zeros(3), epsilon)
    good = [torch.zeros(8, 6), torch.zeros(8), torch.zeros(3, 8), torch.zeros(3)]
    with pytest.raises(ValueError, match="ε must be a positive"):
        load_nbrdf(_saved_nbrdf(tmp_path, good, epsilon=-1.0))
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "best.pt").write_bytes((run_dir / "best.pt").read_bytes())
    saved = dict(np.load(run_dir / "mapping.npz"))
    np.savez(folder / "mapping.npz", **{**saved, "epsilon": np.float64(0.0)})
    with pytest.raises(ValueError, match="mapping.npz: epsilon: the mapping's ε"):
        frenbrdf.Model.load(folder)


# --------------------------------------------------------------------------- messages that mislead


def test_messages_name_what_is_wrong_and_never_advise_unsafe_loading(tmp_path, model):
    random = tmp_path / "random"
    random.write_bytes(os.urandom(4096))
    for suffix, reader in ((".npz", read_samples), (".pt", read_material), (".pt", frenbrdf.Model.load)):
        path = random.with_suffix(suffix)
        path.write_bytes(random.read_bytes())
        with pytest.raises(ValueError) as error:
            reader(path)
        assert str(path) in str(error.value)
        assert "pickle" not in str(error.value) and "weights_only" not in str(error.value)
    pickled = tmp_path / "pickled.pt"
    torch.save({"params": [object]}, pickled)  # a class: weights_only refuses it
    with pytest.raises(ValueError, match="objects other than tensors") as error:
        load_nbrdf(pickled)
    assert "weights_only" not in str(error.value)
    good = tmp_path / "good.pt"
    write_material(good, model.decode(np.zeros(model.config.encoder.latent)).weights())
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(good.read_bytes()[:-200])
    with pytest.raises(ValueError, match="truncated.pt: not a readable saved NBRDF") as error:
        load_nbrdf(truncated)
    assert "Errno" not in str(error.value)
    latin = tmp_path / "latin.csv"
    latin.write_bytes(b"wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b\n" + "é,1".encode("latin-1"))
    with pytest.raises(ValueError, match="latin.csv: not UTF-8 text"):
        read_samples(latin)
    with pytest.raises(ValueError, match=r"^z must have shape \(8,\) or \(B, 8\), got \(4,\)$"):
        model.decode(np.zeros(4))
    with pytest.raises(ValueError, match="^z must be finite"):
        model.decode(np.full(8, np.nan))


def test_a_merl_file_with_no_valid_bin_says_so(tmp_path):
    path = tmp_path / "empty.binary"
    frenbrdf.write_merl(path, -np.ones((3, 90, 90, 180)))
    with pytest.raises(ValueError, match="empty.binary: the MERL table holds no bin measured in every channel"):
        read_samples(path)


def test_errors_name_the_path_given_not_a_temporary_one(tmp_path):
    from frenbrdf.io.atomic import write_text

    too_long = tmp_path / ("x" * 300 + ".txt")  # the temporary is written, the rename to this name fails
    with pytest.raises(OSError) as error:
        write_text(too_long, "x")
    assert error.value.filename == str(too_long) and list(tmp_path.iterdir()) == []
    with pytest.raises(FileNotFoundError) as error:
        frenbrdf.write_merl(tmp_path / "absent" / "x.binary", np.zeros((3, 90, 90, 180)))
    assert str(error.value).endswith(f"'{tmp_path / 'absent' / 'x.binary'}'") and ".tmp" not in str(error.value)


def test_every_output_gets_the_same_permissions(tmp_path):
    from frenbrdf.render.renderer import save_png

    frenbrdf.write_merl(tmp_path / "m.binary", np.zeros((3, 90, 90, 180)))
    save_png(tmp_path / "r.png", np.zeros((8, 8, 3)))
    modes = {stat.S_IMODE(p.stat().st_mode) for p in tmp_path.iterdir()}
    assert len(modes) == 1, modes
