"""The commands fuzzed as a hostile or careless user would use them: crafted files (made here, never committed)
and drawn option values, through ``frenbrdf.cli.main`` as the shell runs it.

Every case must end as a user expects: exit 0 with a result, or exit 2 with one line
``frenbrdf CMD: error: …`` (argparse puts the usage above a refused option value; no traceback, no other exit); every file that was there before is unchanged.
The ``slow`` cases run the large inputs in a child process under an address-space cap, so an abort or a
memory blow-up shows as what it is. ``test_the_suite_counts`` prints the outcome counts of a run.
"""

from __future__ import annotations

import collections
import hashlib
import io
import json
import os
import resource
import subprocess
import sys
import zipfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import frenbrdf
from frenbrdf import cli

from .conftest import constant_table, random_layers, write_keras_h5
from .io.test_bsdf_native import flat_material, tensor_file
from .test_fuzz import VALID

OUTCOMES: collections.Counter = collections.Counter()  # (command, outcome) over the run: the suite's counts


def _hashes(root: Path) -> dict[str, str]:
    found = {}
    for folder, _, files in os.walk(root):
        for name in files:
            path = Path(folder) / name
            if path.is_file() and not path.is_fifo():
                found[str(path.relative_to(root))] = hashlib.sha256(path.read_bytes()).hexdigest()
    return found


def run_as_user(argv: list[str], root: Path, capsys) -> int:
    """Runs the command; asserts the outcome is a result (0) or a one-line error (2) and that nothing under
    ``root`` that was there before changed. Returns the exit code."""
    before = _hashes(root)
    capsys.readouterr()
    try:
        code = cli.main(argv)
    except SystemExit as exit:
        code = exit.code
    err = capsys.readouterr().err
    OUTCOMES[(argv[0], "result" if code == 0 else "error")] += 1
    assert code in (0, 2), f"exit {code}: {err}"
    if code == 2:  # one line; argparse's refusals of an option's value put its usage above it
        lines = err.strip().splitlines()
        assert lines[-1].startswith(f"frenbrdf {argv[0]}: error: ") and "Traceback" not in err, err
        assert len(lines) == 1 or lines[0].startswith("usage: "), err
    after = _hashes(root)
    assert {k: v for k, v in after.items() if k in before} == before, "a file that was there before changed"
    return code


# --- the corpus: crafted files of every kind a user can hand us ----------------------------------------------------


def _npz_with_header(shape: tuple, dtype: str = "<f8") -> bytes:
    """An .npz whose one member declares ``shape`` but holds 8 bytes of data."""
    header = f"{{'descr': '{dtype}', 'fortran_order': False, 'shape': {shape}, }}".encode()
    header += b" " * (63 - (10 + len(header)) % 64) + b"\n"
    member = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header + b"\0" * 8
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("wi_x.npy", member)
    return buffer.getvalue()


def _pickled_npz() -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, wi_x=np.array([{"a": 1}], dtype=object))
    return buffer.getvalue()


def _h5_link_loop(path: Path) -> None:
    with h5py.File(path, "w") as file:
        file["dense_1/dense_1/kernel:0"] = h5py.SoftLink("/dense_1/dense_1/kernel:0")


def _csv(values: str) -> bytes:
    return ("wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b\n" + "\n".join(f"0,0.6,0.8,0,-0.6,0.8,{values}" for _ in range(60))
            + "\n").encode()


def _astm(row: str | None, values: str = "R,G,B", scatter: str = "BRDF") -> bytes:
    """An ASTM E1392 file of 60 copies of ``row`` (numbers, commas between them); None: the header alone."""
    header = f"SCATTER_TYPE {scatter}\nNUM_POINTS 60\nVARS theta_i,phi_i,theta_s,phi_s,{values}\n"
    return (header + ("" if row is None else "\n".join(row for _ in range(60)) + "\n")).encode()


def corpus(folder: Path) -> dict[str, Path]:
    """Crafted files by name; written once per session."""
    folder.mkdir(parents=True, exist_ok=True)
    made: dict[str, bytes] = {
        "empty.csv": b"", "empty.bsdf": b"", "empty.binary": b"", "empty.pt": b"", "empty.h5": b"",
        "random.bsdf": bytes(range(256)) * 8, "random.binary": bytes(range(256)) * 8,
        "random.h5": bytes(range(256)) * 8, "random.npz": bytes(range(256)) * 8,
        "half.bsdf": VALID[".bsdf"][: len(VALID[".bsdf"]) // 2], "half.csv": VALID[".csv"][: len(VALID[".csv"]) // 2],
        "half.npz": VALID[".npz"][: len(VALID[".npz"]) // 2], "half.pt": VALID[".pt"][: len(VALID[".pt"]) // 2],
        "nan.csv": _csv("nan,0.1,0.1"), "inf.csv": _csv("inf,0.1,0.1"), "negative.csv": _csv("-1,0.1,0.1"),
        "huge-value.csv": _csv("1e300,0.1,0.1"), "at-limit.csv": _csv("1e8,1e8,1e8"),
        "text.csv": _csv("red,green,blue"), "few-columns.csv": b"a,b\n1,2\n",
        "empty.astm": b"", "random.astm": bytes(range(256)) * 8,
        "half.astm": VALID[".astm"][: len(VALID[".astm"]) // 2],
        "nan.astm": _astm("0.5,0,0.5,3.1,nan,0.1,0.1"), "degrees.astm": _astm("30,0,30,180,0.1,0.1,0.1"),
        "negative.astm": _astm("0.5,0,0.5,3.1,-0.01,0.1,0.1"), "header-only.astm": _astm(None),
        "btdf.astm": _astm("0.5,0,0.5,3.1,0.1", values="BTDF", scatter="BTDF"),
        "header-bomb.npz": _npz_with_header((100_000_000_000,)), "pickled.npz": _pickled_npz(),
        "huge-values.bsdf": tensor_file(flat_material(colour=(1e44, 1e44, 1e44))),
        "bad-magic.bsdf": tensor_file(flat_material(), magic=b"not_a_tensor"),
        "nested.json": b"[" * 100_000 + b"]" * 100_000, "not-json.json": b"{epochs: 3",
        "list.json": b"[1, 2, 3]", "wrong-types.json": json.dumps({"epochs": "many", "lr": [1]}).encode(),
    }
    for name, content in made.items():
        (folder / name).write_bytes(content)
    with open(folder / "sparse.bsdf", "wb") as file:  # 20 GB that the file system does not hold
        file.truncate(20 << 30)
    _h5_link_loop(folder / "loop.h5")
    write_keras_h5(folder / "wide.h5", random_layers([6, 3]))
    os.mkfifo(folder / "fifo.json")
    os.mkfifo(folder / "fifo.csv")
    (folder / "loop-a.csv").symlink_to(folder / "loop-b.csv")
    (folder / "loop-b.csv").symlink_to(folder / "loop-a.csv")
    (folder / "folder.binary").mkdir()
    frenbrdf.write_merl(folder / "grey.binary", constant_table(0.1))
    return {path.name: path for path in folder.iterdir()}


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    return corpus(tmp_path_factory.mktemp("corpus"))


READERS = {  # the commands that read a material or samples, as argv given the input and a fresh output
    "reconstruct": lambda f, o: ["reconstruct", str(f), "--out", str(o), "--refine", "none", "--quiet"],
    "render": lambda f, o: ["render", str(f), "--out", str(o / "x.png"), "--resolution", "16"],
    "convert": lambda f, o: ["convert", str(f), str(o / "x.csv"), "--samples", "60"],
    "spectrum": lambda f, o: ["spectrum", str(f), "--out", str(o), "--lmax", "5"],
    "import-nbrdf": lambda f, o: ["import-nbrdf", str(f), str(o), "--quiet"],
}
BAD_FILES = ["empty.csv", "empty.bsdf", "empty.binary", "empty.pt", "empty.h5", "random.bsdf", "random.binary",
             "random.h5", "random.npz", "half.bsdf", "half.csv", "half.npz", "half.pt", "nan.csv", "inf.csv",
             "negative.csv", "huge-value.csv", "text.csv", "few-columns.csv", "header-bomb.npz", "pickled.npz",
             "huge-values.bsdf", "bad-magic.bsdf", "sparse.bsdf", "loop.h5", "fifo.csv", "loop-a.csv",
             "folder.binary", "empty.astm", "random.astm", "half.astm", "nan.astm", "degrees.astm", "negative.astm",
             "btdf.astm", "header-only.astm"]


def _reader_cases() -> list:
    """Every reader × every bad file; by default each file goes to one reader (in turn), the rest run as ``slow``."""
    commands = sorted(READERS)
    return [pytest.param(command, name, id=f"{command}-{name}",
                         marks=[] if commands[i % len(commands)] == command else [pytest.mark.slow])
            for i, name in enumerate(BAD_FILES) for command in commands]


@pytest.mark.parametrize(("command", "name"), _reader_cases())
def test_every_reader_refuses_a_bad_file_in_one_line(files, tmp_path, capsys, command, name):
    assert run_as_user(READERS[command](files[name], tmp_path / "out"), tmp_path, capsys) == 2


def test_samples_at_the_limit_give_a_bounded_result(files, tmp_path, capsys):
    """Samples of 1e8 (the largest accepted) reconstruct into a table that stays within the same bound."""
    from frenbrdf.io.reflectance import MAX_REFLECTANCE

    out = tmp_path / "out"
    if run_as_user(READERS["reconstruct"](files["at-limit.csv"], out), tmp_path, capsys) == 0:
        table = frenbrdf.read_merl(out / "material.binary")
        assert np.isfinite(table).all() and table.max() <= MAX_REFLECTANCE


CONFIG_COMMANDS = {
    "train": lambda f, d, o: ["train", "--config", str(f), "--data", str(d), "--out", str(o), "--quiet"],
    "select-config": lambda f, d, o: ["select", "--config", str(f), "--data", str(d), "--target-psnr", "30", "--out",
                                      str(o), "--quiet"],
    "select-front": lambda f, d, o: ["select", "--front", str(f), "--data", str(d), "--target-psnr", "30", "--out",
                                     str(o), "--quiet"],
}


@pytest.mark.parametrize("name", ["nested.json", "not-json.json", "list.json", "wrong-types.json", "fifo.json",
                                  "empty.csv", "random.h5"])
@pytest.mark.parametrize("command", sorted(CONFIG_COMMANDS))
def test_every_config_reader_refuses_a_bad_file_in_one_line(files, tmp_path, capsys, command, name):
    data = files["grey.binary"].parent
    assert run_as_user(CONFIG_COMMANDS[command](files[name], data, tmp_path / "out"), tmp_path, capsys) == 2


# --- drawn option values -----------------------------------------------------------------------------------------

NUMBERS = st.sampled_from(["-1", "0", "1", "3", "1e9", "nan", "inf", "-inf", "2.5", "x", "", str(2**64), str(2**31),
                           "99999999999999999999"])
FAST = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@FAST
@given(option=st.sampled_from(["--resolution", "--spp"]), value=NUMBERS)
def test_render_options(files, tmp_path_factory, capsys, option, value):
    if option == "--spp" and value in ("1", "3", str(2**31)):
        return  # a valid spp path-traces with Mitsuba: tests/test_mitsuba.py
    root = tmp_path_factory.mktemp("render")
    argv = ["render", str(files["grey.binary"]), "--out", str(root / "x.png"), option, value]
    run_as_user(argv + (["--mitsuba", "--resolution", "16"] if option == "--spp" else []), root, capsys)


@FAST
@given(option=st.sampled_from(["--n", "--seed"]), value=NUMBERS)
def test_synth_options(tmp_path_factory, capsys, option, value):
    root = tmp_path_factory.mktemp("synth")
    argv = ["synth", str(root / "bank"), option, value, "--quiet"]
    if option == "--seed":
        argv += ["--n", "1"]
    run_as_user(argv, root, capsys)


@FAST
@given(option=st.sampled_from(["--samples", "--seed"]), value=NUMBERS)
def test_convert_options(files, tmp_path_factory, capsys, option, value):
    root = tmp_path_factory.mktemp("convert")
    small = ["--samples", "60"] if option == "--seed" else []  # a valid draw stays cheap
    run_as_user(["convert", str(files["grey.binary"]), str(root / "x.csv"), option, value, *small], root, capsys)


@FAST
@given(value=NUMBERS)
def test_spectrum_lmax(files, tmp_path_factory, capsys, value):
    root = tmp_path_factory.mktemp("spectrum")
    code = run_as_user(["spectrum", str(files["grey.binary"]), "--out", str(root / "s"), "--lmax", value], root,
                       capsys)
    assert code == 2 or value in ("1", "3")  # 0 is refused, never read as "the default"


@FAST
@given(option=st.sampled_from(["--epochs", "--seed", "--render-every"]), value=NUMBERS)
def test_train_options_are_checked_before_any_work(files, tmp_path_factory, capsys, option, value):
    root = tmp_path_factory.mktemp("train")
    data = files["grey.binary"].parent
    # A folder of one material cannot be split for training: a valid option reaches that error, never training.
    run_as_user(["train", "--data", str(data), "--out", str(root / "run"), option, value, "--quiet"], root, capsys)


# --- large inputs, in a child process under an address-space cap -------------------------------------------------

CAP_BYTES = 6 << 30


def _capped(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (CAP_BYTES, CAP_BYTES))

    return subprocess.run([sys.executable, "-m", "frenbrdf.cli", *argv], cwd=cwd, capture_output=True, text=True,
                          timeout=600, preexec_fn=limit)


@pytest.mark.slow
@pytest.mark.parametrize("command", ["reconstruct", "render", "convert", "spectrum"])
def test_a_sparse_20_gb_bsdf_is_refused_under_a_memory_cap(files, tmp_path, command):
    result = _capped(READERS[command](files["sparse.bsdf"], tmp_path / "out"), tmp_path)
    assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr[-2000:]


@pytest.mark.slow
@pytest.mark.parametrize("argv", [["render", "GREY", "--out", "x.png", "--resolution", "8192"],
                                  ["spectrum", "GREY", "--out", "s", "--lmax", "MAXLMAX"]])
def test_the_largest_accepted_sizes_run_under_the_memory_cap(files, tmp_path, argv):
    from frenbrdf.evaluation.spectrum import MAX_SPECTRUM_LMAX

    argv = [str(files["grey.binary"]) if a == "GREY" else str(MAX_SPECTRUM_LMAX) if a == "MAXLMAX" else a
            for a in argv]
    result = _capped(argv, tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]


def test_the_suite_counts(capsys):
    """Prints the outcome counts of the cases run so far in this module (run it last: ``-p no:randomly``)."""
    with capsys.disabled():
        print("\nfuzz outcomes:", dict(sorted(OUTCOMES.items())))
