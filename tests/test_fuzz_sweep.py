"""What the fuzz sweep of 2026-11-30 found, each checked where its class lives: tensors frenbrdf cannot compute with
in any torch file, a writer or evaluator giving values its readers refuse, JSON that is not JSON, a capacity front
whose row would write an untrainable config, −0 as an edit position, too many Keras layers, and Ctrl-C before a
command starts."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf import cli
from frenbrdf.io import read_material
from frenbrdf.io.atomic import json_text, save_json
from frenbrdf.io.nbrdf import MAX_LAYERS
from frenbrdf.io.paths import torch_load

from .conftest import random_layers, write_keras_h5
from .io.test_bsdf_native import flat_material, tensor_file
from .test_hostile import _run


@pytest.fixture(scope="module")
def saved(tmp_path_factory) -> Path:
    """A saved NBRDF (frenbrdf's own .pt)."""
    path = tmp_path_factory.mktemp("saved") / "material.pt"
    weights = read_material(write_keras_h5(path.with_suffix(".h5"), random_layers([6, 8, 8, 3])))
    frenbrdf.io.write_material(path, weights)
    return path


@pytest.mark.parametrize(("change", "message"), [
    (lambda t: t.to("meta"), "has no data (torch's meta device)"),
    (lambda t: t.to_sparse(), "is not dense"),
    (lambda t: t.to(torch.complex64), "not real numbers"),
])
def test_a_tensor_frenbrdf_cannot_compute_with_is_named_in_any_torch_file(saved, tmp_path, capsys, change, message):
    state = torch.load(saved, weights_only=True)
    state["params"][1] = change(state["params"][1])
    torch.save(state, tmp_path / "bad.pt")
    with pytest.raises(ValueError, match=r"bad\.pt: not a valid saved NBRDF: the tensor at \['params'\]\[1\] "):
        torch_load(tmp_path / "bad.pt", "saved NBRDF")
    code, err = _run(["render", tmp_path / "bad.pt", "--out", tmp_path / "x.png", "--resolution", 8], capsys)
    assert code == 2 and message in err and not (tmp_path / "x.png").exists()


def test_half_precision_tensors_are_read_as_float32(saved, tmp_path):
    state = torch.load(saved, weights_only=True)
    state["reference"] = state["reference"].to(torch.bfloat16)
    state["params"] = [p.to(torch.float16) for p in state["params"]]
    torch.save(state, tmp_path / "half.pt")
    weights = read_material(tmp_path / "half.pt")
    assert weights.reference.dtype == np.float32
    assert all(p.dtype == torch.float32 for p in weights.params)


def test_import_nbrdf_refuses_a_network_whose_outputs_no_reader_would_take(tmp_path, capsys):
    layers = random_layers([6, 8, 3])
    layers[-1] = (layers[-1][0], np.full(3, 50.0))  # finite, but exp(50) is no reflectance
    source = write_keras_h5(tmp_path / "big.h5", layers)
    code, err = _run(["import-nbrdf", source, tmp_path / "out", "--quiet"], capsys)
    assert code == 2 and "big.h5" in err and "above 1e+08" in err and not list((tmp_path / "out").glob("*.binary"))


def test_a_bsdf_whose_fields_scale_past_any_reflectance_is_refused_by_every_command(tmp_path, capsys):
    path = tmp_path / "tiny-sigma.bsdf"
    path.write_bytes(tensor_file(flat_material(sigma=1e-12)))
    with pytest.raises(frenbrdf.BsdfFormatError, match=r"tiny-sigma\.bsdf: .* evaluated values are above"):
        frenbrdf.read_bsdf(path)(np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]))
    for argv in (["render", path, "--out", tmp_path / "x.png", "--resolution", 8],
                 ["convert", path, tmp_path / "x.binary"]):
        code, err = _run(argv, capsys)
        assert code == 2 and "tiny-sigma.bsdf" in err, err


def test_json_outputs_hold_no_nan_or_infinity(tmp_path):
    save_json(tmp_path / "a.json", {"mean": math.nan, "rows": [1.0, math.inf, (-math.inf, 2)], "n": 3})
    text = (tmp_path / "a.json").read_text()
    assert json.loads(text, parse_constant=lambda name: pytest.fail(f"{name} in JSON")) == \
        {"mean": None, "rows": [1.0, None, [None, 2]], "n": 3}


def test_a_run_whose_history_holds_a_perfect_render_picks_that_epoch():
    # A validation render equal to its truth has PSNR ∞, which a history.json holds as null.
    from frenbrdf.training.config import selection_score

    history = json.loads(json_text([{"epoch": 0, "val_rec": 0.2, "val_psnr": 30.0},
                                    {"epoch": 1, "val_rec": 0.1, "val_psnr": math.inf}]))
    assert history[1]["val_psnr"] is None
    assert [selection_score(entry, "psnr") for entry in history] == [-30.0, -math.inf]
    assert selection_score({"epoch": 2, "val_rec": 0.1}, "psnr") is None  # not rendered: not judged


def test_a_summary_without_edits_has_no_edit_values():
    from frenbrdf.evaluation.tables import summarise

    summary = summarise([{"rmse": 0.1, "psnr": 30.0, "ssim": 0.9, "lfre": 0.2, "delta_e": 1.0}], [])
    assert summary["psnr"] == 30.0 and summary["edit_psnr"] is None and summary["edit_delta_e"] is None


@pytest.mark.parametrize(("row", "message"), [
    ({"psnr": math.inf}, "has no valid PSNR"),
    ({"psnr": True}, "has no valid PSNR"),
    ({"config": {"epochs": "x"}}, "row 0's config: epochs must be an integer"),
    ({"config": {"model": {"nbrdf": {"hidden": [1_000_000_000]}}}}, "row 0's config"),
    ({"config": {"method": "foo"}}, "row 0's config: method must be one of"),
])
def test_select_refuses_a_front_row_it_could_not_pass_on(tmp_path, toy_materials, capsys, row, message):
    fields = {"name": "small", "psnr": 30.0, "bytes_per_material": 364, "latent_bytes": 32, "config": {}, **row}
    (tmp_path / "front.json").write_text(json.dumps({"chart": "capacity", "rows": [fields]}))
    code, err = _run(["select", "--data", toy_materials, "--target-psnr", 20, "--front", tmp_path / "front.json",
                      "--out", tmp_path / "sel", "--quiet"], capsys)
    assert code == 2 and message in err, err
    assert not (tmp_path / "sel").exists()


def test_minus_zero_is_the_edit_position_zero():
    from frenbrdf.material.edit import check_positions

    with pytest.raises(ValueError, match="positions given twice"):
        check_positions([-0.0, 0.0])
    assert str(check_positions([-0.0])[0]) == "0.0"


def test_a_keras_network_deeper_than_an_nbrdf_is_refused(tmp_path, capsys):
    deep = write_keras_h5(tmp_path / "deep.h5", random_layers([6] + [4] * (MAX_LAYERS + 1) + [3]))
    code, err = _run(["import-nbrdf", deep, tmp_path / "out", "--quiet"], capsys)
    assert code == 2 and f"{MAX_LAYERS + 1} hidden layers; an NBRDF has at most {MAX_LAYERS}" in err
    assert read_material(write_keras_h5(tmp_path / "ok.h5", random_layers([6] + [4] * MAX_LAYERS + [3])))


def test_the_command_line_starts_without_torch():
    """``import frenbrdf`` and the parser load no torch (2 s): --help is quick and a Ctrl-C then is one line."""
    code = "import sys, frenbrdf.cli; frenbrdf.cli.build_parser(); print('torch' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout == "False\n"


def test_ctrl_c_while_an_option_loads_its_module_is_one_line(monkeypatch, capsys):
    from frenbrdf.cli import options

    def interrupted(*args):
        raise KeyboardInterrupt

    monkeypatch.setattr(options.importlib, "import_module", interrupted)
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["synth", "bank", "--n", "1"])
    assert exit_info.value.code == 130 and capsys.readouterr().err == "frenbrdf: interrupted\n"
