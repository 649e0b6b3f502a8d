"""Inputs a hostile or careless user tried after issue 45 that the other suites did not: long and odd names, a
file output in a folder still to be created, upper-case suffixes, NPZ arrays that are not real numbers, angles in
the wrong unit, degenerate or overflowing Keras networks, and messages that must name the user's path on one line.

Each case runs the CLI as the shell does (:func:`frenbrdf.cli.main`) or the reader it reaches, and is fast."""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

import numpy as np
import pytest

import frenbrdf
from frenbrdf import cli
from frenbrdf.data.nbrdf_import import import_nbrdf
from frenbrdf.io import read_material, read_samples
from frenbrdf.io.atomic import NAME_MAX, atomic_path, temporary_name
from frenbrdf.io.keras import read_keras_nbrdf
from frenbrdf.io.outputs import OutputFolder
from frenbrdf.io.samples import FORMS

from .conftest import constant_table, random_layers, write_keras_h5
from .io.test_bsdf_native import flat_material, tensor_file


def _run(argv: list, capsys) -> tuple[int, str]:
    """The exit status and stderr of the CLI; a refusal must be one line ``frenbrdf CMD: error: …``."""
    capsys.readouterr()
    try:
        code = cli.main([str(arg) for arg in argv])
    except SystemExit as exit:
        code = exit.code
    err = capsys.readouterr().err
    if code == 2:
        assert len(err.strip().splitlines()) == 1 and err.startswith(f"frenbrdf {argv[0]}: error: "), err
    return code, err.strip()


def _hashes(root: Path) -> dict[str, str]:
    return {str(p): hashlib.sha256(p.read_bytes()).hexdigest() for p in root.rglob("*") if p.is_file()}


@pytest.fixture(scope="module")
def grey(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("hostile") / "grey.binary"
    frenbrdf.write_merl(path, constant_table(0.1))
    return path


# --- names ---------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["x" * 250 + ".png", "é" * 125 + ".png", "x" * 255])
def test_a_temporary_name_stays_within_name_max_however_long_the_name(name):
    temporary = temporary_name(name)
    assert len(temporary.encode()) <= NAME_MAX and temporary.startswith(".")
    assert temporary.endswith(Path(name).suffix or ".tmp")
    temporary.encode().decode()  # never cut inside a character


@pytest.mark.parametrize(("argv", "name"), [
    (["render", "{grey}", "--out", "{out}", "--resolution", "8"], "r" * 250 + ".png"),
    (["convert", "{grey}", "{out}", "--samples", "60"], "c" * 250 + ".csv"),
])
def test_a_legal_254_byte_output_name_is_written(grey, tmp_path, capsys, argv, name):
    """Once refused after the work: the hidden temporary name beside it was longer than 255 bytes."""
    out = tmp_path / name
    code, err = _run([a.format(grey=grey, out=out) for a in argv], capsys)
    assert code == 0, err
    assert out.is_file() and [p.name for p in tmp_path.iterdir()] == [name]


@pytest.mark.parametrize("argv", [
    ["render", "{grey}", "--out", "{out}/new/x.png", "--resolution", "8"],
    ["convert", "{grey}", "{out}/new/x.csv", "--samples", "60"],
    ["convert", "{grey}", "{out}/new/x.binary"],  # the native MERL writer: frenbrdf.io.merl.write_merl
])
def test_a_file_output_in_a_folder_not_yet_made_is_written(grey, tmp_path, capsys, argv):
    """The check accepts a folder that can be created; render once failed for want of it after rendering."""
    code, err = _run([a.format(grey=grey, out=tmp_path) for a in argv], capsys)
    assert code == 0, err
    assert len(list((tmp_path / "new").iterdir())) == 1


def test_atomic_path_makes_the_missing_folder(tmp_path):
    with atomic_path(tmp_path / "a" / "b" / "page.html") as temporary:
        temporary.write_text("x")
    assert (tmp_path / "a" / "b" / "page.html").read_text() == "x"


def test_an_error_naming_a_path_with_a_line_break_stays_one_line(tmp_path, capsys):
    bad = tmp_path / "bad\nname.binary"
    bad.write_bytes(b"junk")
    code, err = _run(["render", bad, "--out", tmp_path / "x.png"], capsys)
    assert code == 2 and "bad\\nname.binary" in err, err
    code, err = _run(["render", tmp_path, "--out", tmp_path / "x.png"], capsys)
    assert code == 2 and "Errno" not in err and f"{tmp_path}: material file expected, got a folder" in err, err


def test_a_staged_writers_error_names_the_output_not_the_hidden_staging_folder(tmp_path):
    folder = OutputFolder.claim(tmp_path / "out", command="synth")
    with pytest.raises(ValueError) as caught, folder.staged() as staging:
        raise ValueError(f"{staging / 'a.binary'}: cannot write non-finite value inf")
    assert str(caught.value) == f"{tmp_path / 'out' / 'a.binary'}: cannot write non-finite value inf"
    assert not (tmp_path / "out").exists() and not list(tmp_path.iterdir())


# --- readers -------------------------------------------------------------------------------------------------------


def test_every_single_file_reader_takes_upper_case_suffixes(tmp_path):
    """render, view and spectrum read through frenbrdf.io.read_material, whose forerunner once matched suffixes
    case-sensitively."""
    (tmp_path / "M.BSDF").write_bytes(tensor_file(flat_material()))
    write_keras_h5(tmp_path / "K.H5", random_layers([6, 8, 3]))
    assert callable(read_material(tmp_path / "M.BSDF"))
    assert read_material(tmp_path / "K.H5").what == "Keras NBRDF"


def _npz(path: Path, convert) -> Path:
    rng = np.random.default_rng(0)
    wi, wo = (np.abs(rng.normal(size=(60, 3))) + 0.2 for _ in range(2))
    wi, wo = (d / np.linalg.norm(d, axis=1, keepdims=True) for d in (wi, wo))
    columns = np.concatenate([wi, wo, np.full((60, 3), 0.1)], axis=1)
    np.savez(path, **{name: convert(columns[:, i]) for i, name in enumerate(FORMS["vectors"])})
    return path


@pytest.mark.parametrize(("kind", "convert"), [
    ("complex128", lambda c: c + 1j), ("<U32", lambda c: c.astype(str)), ("bool", lambda c: c > 0),
    ("datetime64[s]", lambda c: np.zeros(len(c), "datetime64[s]")),
])
def test_npz_arrays_must_be_real_numbers(tmp_path, kind, convert):
    """numpy once turned these into numbers without a word (text parsed, an imaginary part dropped)."""
    path = _npz(tmp_path / "samples.npz", convert)
    with pytest.raises(ValueError, match=re.escape(f"{path}: array wi_x holds {kind} values; the arrays must be real")):
        read_samples(path)


def test_npz_of_integers_or_half_floats_is_still_read(tmp_path):
    assert len(read_samples(_npz(tmp_path / "samples.npz", lambda c: c.astype(np.float16)))) == 60


@pytest.mark.parametrize(("header", "row", "message"), [
    ("theta_i,phi_i,theta_o,phi_o,r,g,b", "45,0,30,180,0.1,0.1,0.1",
     r"row 2: theta_i is 45, outside 0 … 1.5708 rad \(above the surface; angles in degrees go in columns named "),
    ("theta_i,phi_i,theta_o,phi_o,r,g,b", "0.3,0,-0.2,1,0.1,0.1,0.1", r"row 2: theta_o is -0.2, outside 0 … 1.5708"),
    ("theta_i_deg,phi_i_deg,theta_o_deg,phi_o_deg,r,g,b", "30,0,90,0,0.1,0.1,0.1", r"theta_o_deg is 90, outside 0 … 90°"),
])
def test_angles_outside_the_hemisphere_or_in_the_wrong_unit_are_refused(tmp_path, header, row, message):
    """45 in a radians column (degrees meant) once wrapped round to a direction above the surface and was read."""
    path = tmp_path / "samples.csv"
    path.write_text(header + "\n" + "\n".join([row] * 60) + "\n")
    with pytest.raises(ValueError, match=message):
        read_samples(path)


def test_a_zero_wide_keras_layer_is_refused_by_the_reader(tmp_path):
    path = write_keras_h5(tmp_path / "w.h5", [(np.zeros((6, 0)), np.zeros(0)), (np.zeros((0, 3)), np.zeros(3))])
    with pytest.raises(ValueError, match=rf"{path}: layer 'dense_1' is 0 wide; an NBRDF's layers are 1 … \d+ wide"):
        read_keras_nbrdf(path)


def test_an_overflowing_keras_network_is_named_and_nothing_is_written(tmp_path):
    """Finite weights of 1e30: exp(x) − 1 overflows; the message once named a hidden staging file."""
    path = write_keras_h5(tmp_path / "big.h5", [(np.full(k.shape, 1e30), b) for k, b in random_layers([6, 4, 3])])
    with pytest.raises(ValueError, match=rf"^{path}: [\d,]+ of its network outputs at the MERL bins .* are NaN or infinite"):
        import_nbrdf([path], tmp_path / "out", progress=False)
    assert sorted(os.listdir(tmp_path)) == ["big.h5"]


def test_a_table_without_a_measured_bin_is_named_by_spectrum(tmp_path, capsys):
    table = -np.ones((3, 90, 90, 180))
    path = tmp_path / "missing.binary"
    frenbrdf.write_merl(path, table, physical_units=False)
    before = _hashes(tmp_path)
    code, err = _run(["spectrum", path, "--out", tmp_path / "out", "--lmax", "3"], capsys)
    assert code == 2 and f"error: {path}: the table holds no valid bin" in err, err
    assert _hashes(tmp_path) == before
