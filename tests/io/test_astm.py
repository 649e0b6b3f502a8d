"""ASTM E1392 files (frenbrdf.io.astm): files written here from the format's description (a keyword header, VARS,
NUM_POINTS, one comma-separated row per configuration in radians) read as the samples they hold; what frenbrdf
writes reads back, in frenbrdf and through the commands; every malformed file is refused naming its line."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import frenbrdf
from frenbrdf import cli
from frenbrdf.io import FORMATS, read_samples, write_samples
from frenbrdf.io import astm as astm_module
from frenbrdf.io.astm import MAX_LINE, read_astm_samples, write_astm_samples
from frenbrdf.io.samples import MIN_SAMPLES, Measurements

N = MIN_SAMPLES + 10
HEADER = ["SOURCE goniometer-7", 'SAMPLE_NAME "blue paint, matte"', "DATE 2026-11-27", "FORMAT ASCII",
          "WAVELENGTH 550nm", "POLARIZATION unpolarized", "SCATTER_TYPE BRDF"]


def _angles(n: int = N, seed: int = 0) -> np.ndarray:
    """``(n, 4)`` θ_i, φ_i, θ_s, φ_s in radians: θ in [0, π/2] (both ends included), φ beyond ±π too."""
    rng = np.random.default_rng(seed)
    theta, phi = rng.uniform(0, np.pi / 2, (2, n)), rng.uniform(-4, 8, (2, n))
    theta[0, :2], theta[1, :2] = (0.0, np.pi / 2), (np.pi / 2, 0.0)
    return np.stack([theta[0], phi[0], theta[1], phi[1]], axis=1)


def _direction(theta, phi):
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def _astm(path, rows, vars_="theta_i,phi_i,theta_s,phi_s,R,G,B", header=HEADER, points=None, separator=","):
    """An ASTM E1392 file as a gonioreflectometer writes it; ``points``: NUM_POINTS (default: the rows)."""
    lines = [*header, f"NUM_POINTS {len(rows) if points is None else points}", f"VARS {vars_}"]
    lines += [separator.join(repr(float(v)) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def _measurements(n: int = N, seed: int = 3) -> Measurements:
    rng = np.random.default_rng(seed)
    angles = _angles(n, seed)
    wi, wo = _direction(angles[:, 0], angles[:, 1]), _direction(angles[:, 2], angles[:, 3])
    return Measurements(rng.uniform(0, 3, (n, 3)), wi, wo)


# --------------------------------------------------------------------------- reading


def test_an_rgb_file_reads_as_its_samples(tmp_path):
    rng = np.random.default_rng(1)
    angles, values = _angles(), rng.uniform(0, 5, (N, 3))
    values[3] = 0.0  # a black sample is a sample
    text = _astm(tmp_path / "x.astm", np.concatenate([angles, values], axis=1)).read_text().splitlines()
    # Comments, blank lines, spaces around commas, CRLF line ends and upper-case VARS: all as good.
    text.insert(0, "# exported by the lab's goniometer")
    text.insert(6, "")
    text = [line.replace(",", " , ") if line[:1].isdigit() else line for line in text]
    text = [line.replace("VARS theta_i,phi_i,theta_s,phi_s", "VARS THETA_I,Phi_i,theta_S,PHI_S") for line in text]
    text.insert(20, "# a comment among the rows")
    path = tmp_path / "lab.astm"
    path.write_bytes(("\r\n".join(text) + "\r\n").encode())

    samples = read_astm_samples(path)
    assert samples.kind == "astm" and samples.source == str(path) and len(samples) == N and samples.truth is None
    np.testing.assert_array_equal(samples.values, values)
    np.testing.assert_allclose(samples.wi, _direction(angles[:, 0], angles[:, 1]), rtol=0, atol=1e-15)
    np.testing.assert_allclose(samples.wo, _direction(angles[:, 2], angles[:, 3]), rtol=0, atol=1e-15)
    # θ_i = 0 is the normal; θ = π/2 is the horizon's edge, still above it.
    np.testing.assert_allclose(samples.wi[0], [0, 0, 1], atol=0)
    assert samples.wi[1, 2] > 0 and samples.wo[0, 2] > 0
    # read_samples reaches it by its suffix, in any case.
    np.testing.assert_array_equal(read_samples(path).values, values)
    loud = tmp_path / "LAB.ASTM"
    loud.write_bytes(path.read_bytes())
    assert read_samples(loud).kind == "astm"


@pytest.mark.parametrize("column", ["BRDF", "brdf", "Y", "550nm"])
@pytest.mark.parametrize("separator", [",", "  "])
def test_one_value_column_reads_as_grey(tmp_path, column, separator):
    rng = np.random.default_rng(2)
    angles, value = _angles(), rng.uniform(0, 2, (N, 1))
    path = _astm(tmp_path / "grey.astm", np.concatenate([angles, value], axis=1),
                 vars_=f"theta_i,phi_i,theta_s,phi_s,{column}", separator=separator)
    samples = read_samples(path)
    np.testing.assert_array_equal(samples.values, np.repeat(value, 3, axis=1))


def test_the_directions_point_away_from_the_surface(tmp_path):
    """(θ_i, φ_i) is the light's direction, (θ_s, φ_s) the viewer's: the mirror direction is (θ_i, φ_i + π)."""
    angles = _angles()
    rows = np.concatenate([angles[:, :2], angles[:, :1], angles[:, 1:2] + np.pi, np.full((N, 1), 0.5)], axis=1)
    samples = read_samples(_astm(tmp_path / "mirror.astm", rows, vars_="theta_i,phi_i,theta_s,phi_s,BRDF"))
    mirror = samples.wi * [-1, -1, 1]
    np.testing.assert_allclose(samples.wo, mirror, atol=1e-15)


# --------------------------------------------------------------------------- writing


def test_the_writer_writes_the_header_and_rows_the_reader_reads_exactly(tmp_path):
    written = _measurements()
    path = tmp_path / "paint sample.astm"
    write_astm_samples(path, written)
    lines = path.read_text().splitlines()
    assert lines[:5] == [f"SOURCE frenbrdf {frenbrdf.__version__}", 'SAMPLE_NAME "paint sample"', "SCATTER_TYPE BRDF",
                         f"NUM_POINTS {N}", "VARS theta_i,phi_i,theta_s,phi_s,R,G,B"]
    assert len(lines) == 5 + N and all(len(line.split(",")) == 7 for line in lines[5:])
    read = read_samples(path)
    np.testing.assert_array_equal(read.values, written.values)
    for name in ("wi", "wo"):
        np.testing.assert_allclose(getattr(read, name), getattr(written, name), rtol=0, atol=1e-15)
    # Angles in radians, θ within 0 … π/2.
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[5:]])
    assert rows[:, [0, 2]].min() >= 0 and rows[:, [0, 2]].max() <= np.pi / 2
    # A name given, one that would break the header made safe; written atomically (nothing else left beside it).
    write_astm_samples(path, written, sample_name='say "hi"\nthere')
    assert path.read_text().splitlines()[1] == 'SAMPLE_NAME "say _hi__there"'
    np.testing.assert_array_equal(read_samples(path).values, written.values)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["paint sample.astm"]
    with pytest.raises(TypeError, match=r"x\.astm: a file of samples holds Measurements"):
        write_samples(tmp_path / "x.astm", np.zeros((N, 9)))


def test_csv_to_astm_to_csv_is_the_same_to_float64(tmp_path):
    first = tmp_path / "first.csv"
    write_samples(first, _measurements(seed=8))
    original = read_samples(first)
    write_samples(tmp_path / "m.astm", original)
    write_samples(tmp_path / "again.csv", read_samples(tmp_path / "m.astm"))
    again = read_samples(tmp_path / "again.csv")
    np.testing.assert_array_equal(again.values, original.values)  # exactly: the shortest repr both ways
    for name in ("wi", "wo"):  # through angles: to float64's precision
        np.testing.assert_allclose(getattr(again, name), getattr(original, name), rtol=0, atol=1e-15)


def test_the_table_of_formats_reads_and_writes_astm():
    entry = FORMATS[".astm"]
    assert (entry.role, entry.read, entry.write) == ("samples", read_astm_samples, write_astm_samples)


# --------------------------------------------------------------------------- through the commands


def test_convert_turns_samples_into_astm_and_back(tmp_path, capsys):
    write_samples(tmp_path / "m.csv", _measurements(seed=4))
    write_samples(tmp_path / "m.npz", _measurements(seed=4))
    original = read_samples(tmp_path / "m.csv")
    for source in ("m.csv", "m.npz"):
        assert cli.main(["convert", str(tmp_path / source), str(tmp_path / "out.astm"), "--overwrite"]) == 0
        np.testing.assert_array_equal(read_samples(tmp_path / "out.astm").values, original.values)
    assert cli.main(["convert", str(tmp_path / "out.astm"), str(tmp_path / "back.csv")]) == 0
    back = read_samples(tmp_path / "back.csv")
    np.testing.assert_array_equal(back.values, original.values)
    np.testing.assert_allclose(back.wi, original.wi, rtol=0, atol=1e-15)
    # A MERL table into ASTM samples; samples into a table, or --samples for a file of samples: refused.
    frenbrdf.write_merl(tmp_path / "grey.binary", np.full((3, 90, 90, 180), 0.2))
    assert cli.main(["convert", str(tmp_path / "grey.binary"), str(tmp_path / "grey.astm"), "--samples", "60"]) == 0
    assert len(read_samples(tmp_path / "grey.astm")) == 60
    # A device's pairs rather than random bins: the samples `read_samples` draws with that pattern, to the file.
    assert cli.main(["convert", str(tmp_path / "grey.binary"), str(tmp_path / "gonio.astm"), "--samples", "300",
                     "--pattern", "gonioreflectometer", "--seed", "3"]) == 0
    drawn = read_samples(tmp_path / "grey.binary", samples=300, seed=3, pattern="gonioreflectometer")
    written = read_samples(tmp_path / "gonio.astm")
    np.testing.assert_array_equal(written.values, drawn.values)
    for side in ("wi", "wo"):
        np.testing.assert_allclose(getattr(written, side), getattr(drawn, side), rtol=0, atol=1e-15)
    assert not np.allclose(written.wi, read_samples(tmp_path / "grey.binary", samples=300, seed=3).wi)
    capsys.readouterr()
    for argv, message in (
            (["convert", str(tmp_path / "grey.binary"), str(tmp_path / "t.binary"), "--pattern", "in-plane"],
             "--pattern picks the samples a .csv, .npz or .astm output holds; a .binary output is the whole table"),
            (["convert", str(tmp_path / "out.astm"), str(tmp_path / "x.csv"), "--pattern", "in-plane"],
             "--pattern picks samples from a MERL file or a .bsdf; " + str(tmp_path / "out.astm") + " is a file"),
            (["convert", str(tmp_path / "grey.binary"), str(tmp_path / "x.csv"), "--pattern", "in-plane",
              "--samples", "all"], "--samples all draws every MERL bin; --pattern in-plane draws N pairs"),
            (["convert", str(tmp_path / "out.astm"), str(tmp_path / "t.binary")],
             "out.astm: scattered samples make no MERL table (t.binary); `frenbrdf reconstruct out.astm"),
            (["convert", str(tmp_path / "out.astm"), str(tmp_path / "x.csv"), "--samples", "60"],
             "--samples picks samples from a MERL file or a .bsdf; " + str(tmp_path / "out.astm") + " is a file")):
        with pytest.raises(SystemExit) as stop:
            cli.main(argv)
        assert stop.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "t.binary").exists() and not (tmp_path / "x.csv").exists()


@pytest.mark.pretrained
def test_reconstruct_and_render_an_astm_file(tmp_path, capsys):
    """The shipped model, encoder only: an .astm is a file of samples like any other."""
    table = np.full((3, 90, 90, 180), 0.15)
    frenbrdf.write_merl(tmp_path / "grey.binary", table)
    write_samples(tmp_path / "grey.astm", read_samples(tmp_path / "grey.binary", samples=300, seed=1))
    out = tmp_path / "result"
    assert cli.main(["reconstruct", str(tmp_path / "grey.astm"), "--out", str(out), "--refine", "none", "--quiet",
                     "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["input"] == {"path": str(tmp_path / "grey.astm"), "kind": "astm", "samples": 300}
    assert cli.main(["render", str(out / "material.pt"), "--out", str(tmp_path / "x.png"), "--resolution", "16"]) == 0
    assert (tmp_path / "x.png").stat().st_size > 0
    with pytest.raises(SystemExit) as stop:
        cli.main(["reconstruct", str(tmp_path / "grey.astm"), "--out", str(tmp_path / "r2"), "--samples", "100"])
    assert stop.value.code == 2 and "is a file of samples, read whole" in capsys.readouterr().err


# --------------------------------------------------------------------------- what is refused


def _rows(n: int = N, values: int = 3) -> list[str]:
    angles = _angles(n)
    return [",".join(repr(float(v)) for v in [*row, *[0.5] * values]) for row in angles]


def _text(*, header=("SCATTER_TYPE BRDF",), points: int | str | None = N, vars_="theta_i,phi_i,theta_s,phi_s,R,G,B",
          rows=None) -> str:
    lines = list(header)
    lines += [f"NUM_POINTS {points}"] if points is not None else []
    lines += [f"VARS {vars_}"] if vars_ is not None else []
    return "\n".join([*lines, *(_rows() if rows is None else rows)]) + "\n"


def _with_row(index: int, row: str) -> list[str]:
    rows = _rows()
    rows[index] = row
    return rows


# The header above the rows is 3 lines: a row of index k is on line k + 4.
MALFORMED = {
    "empty": ("", r"the file is empty \(an ASTM E1392 header and rows of samples are needed\)"),
    "blank": ("\n\n  \n", r"the file is empty"),
    "header-only": (_text(rows=[]), r"no rows of samples after the header \(NUM_POINTS says 60\)"),
    "comments-only": ("# nothing\n# here\n", r"no VARS line: an ASTM E1392 header names the columns, e\.g\. VARS "),
    "no-vars": (_text(vars_=None), r"no VARS line before the first row \(line 3\): an ASTM E1392 header names the "
                                   r"columns"),
    "no-num-points": (_text(points=None), r"no NUM_POINTS line before the first row \(line 3\): an ASTM E1392 header "
                                          r"names the number of rows"),
    "vars-without-angles": (_text(vars_="x,y,R,G,B"), r"line 3: VARS x,y,R,G,B: the columns must start with the "
                                                      r"angles theta_i,phi_i,theta_s,phi_s"),
    "vars-angles-in-another-order": (_text(vars_="theta_s,phi_s,theta_i,phi_i,R,G,B"),
                                     r"line 3: VARS .*: the columns must start with the angles"),
    "vars-btdf": (_text(vars_="theta_i,phi_i,theta_s,phi_s,BTDF"),
                  r"line 3: VARS .*: after the angles, frenbrdf reads R,G,B or one BRDF value column \(BRDF, Y or a "
                  r"wavelength such as 550nm\), got BTDF"),
    "vars-no-values": (_text(vars_="theta_i,phi_i,theta_s,phi_s"), r"line 3: VARS .*, got none"),
    "vars-xyz": (_text(vars_="theta_i,phi_i,theta_s,phi_s,X,Y,Z"), r"line 3: VARS .*: CIE XYZ values; frenbrdf reads "
                                                                   r"R,G,B"),
    "vars-spectral": (_text(vars_="theta_i,phi_i,theta_s,phi_s,450nm,550nm,650nm,700nm"),
                      r"line 3: VARS .*: 4 wavelengths \(spectral data\)"),
    "vars-twice-named": (_text(vars_="theta_i,phi_i,theta_s,phi_s,R,G,g"), r"line 3: VARS .*: a column is named twice"),
    "vars-twice": (_text(header=("VARS theta_i,phi_i,theta_s,phi_s,BRDF",)),
                   r"line 3: VARS is given twice \(first on line 1\)"),
    "num-points-fewer": (_text(points=N + 5), r"NUM_POINTS \(line 2\) says 65 rows, the file holds 60 \(cut short\?\)"),
    "num-points-more": (_text(points=N - 1), r"NUM_POINTS \(line 2\) says 59 rows, the file holds 60$"),
    "num-points-text": (_text(points="many"), r"line 2: NUM_POINTS must be a whole number of rows, got 'many'"),
    "num-points-too-many": (_text(points=10**9), r"line 2: NUM_POINTS says 1,000,000,000 samples; give at most "
                                                 r"4,000,000"),
    "num-points-empty": (_text(points=""), r"line 2: NUM_POINTS without a value"),
    "few-columns": (_text(rows=_with_row(7, "0.1,0.2,0.3,0.4,0.5,0.6")),
                    r"line 11: 6 values, VARS names 7 columns \(theta_i,phi_i,theta_s,phi_s,R,G,B\)"),
    "many-columns": (_text(rows=_with_row(0, "0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8")), r"line 4: 8 values, VARS names 7"),
    "text": (_text(rows=_with_row(2, "0.1,0.2,0.3,0.4,0.5,red,0.7")), r"line 6, column G: 'red' is not a number"),
    "empty-cell": (_text(rows=_with_row(2, "0.1,0.2,0.3,0.4,,0.6,0.7")), r"line 6, column R: '' is not a number"),
    "nan": (_text(rows=_with_row(5, "0.1,0.2,0.3,0.4,nan,0.6,0.7")),
            r"line 9: R is NaN or infinite \(1 such line\(s\) in all\)"),
    "inf-angle": (_text(rows=_with_row(4, "0.1,inf,0.3,0.4,0.5,0.6,0.7")), r"line 8: phi_i is NaN or infinite"),
    "degrees": (_text(rows=[f"45,{30 * k},60,{30 * k + 180},0.5,0.5,0.5" for k in range(N)]),
                r"line 4: theta_i is 45, above π/2 \(1\.5708\): angles must be radians, θ from the normal in "
                r"0 … π/2 \(is the file in degrees\?\) \(60 such line\(s\) in all\)"),
    "theta-negative": (_text(rows=_with_row(9, "0.1,0.2,-0.3,0.4,0.5,0.6,0.7")),
                       r"line 13: theta_s is -0.3, negative: θ is measured from the normal, 0 … π/2"),
    "negative-value": (_text(rows=_with_row(3, "0.1,0.2,0.3,0.4,0.5,-0.001,0.7")),
                       r"line 7: G is -0.001, negative \(BRDF values must be ≥ 0: clip or drop the noise below 0 "
                       r"before\) \(1 such line\(s\) in all\)"),
    "too-bright": (_text(rows=_with_row(3, "0.1,0.2,0.3,0.4,1e9,0.6,0.7")), r"line 7: reflectance above 1e\+08 1/sr"),
    "scatter-type": (_text(header=("SCATTER_TYPE BTDF",)), r"line 1: SCATTER_TYPE BTDF: frenbrdf reads BRDF "
                                                           r"\(reflected light\) only"),
    "scatter-type-twice": (_text(header=("SCATTER_TYPE BRDF", "SCATTER_TYPE BRDF")),
                           r"line 2: SCATTER_TYPE is given twice"),
    "bad-header-line": (_text(header=("SOURCE lab", "= 3")),
                        r"line 2: '= 3' is neither a header line \(KEYWORD value\) nor a row of numbers"),
    "open-quote": (_text(header=('SAMPLE_NAME "blue paint',)),
                   r"line 1: SAMPLE_NAME's value \"blue paint opens a quote it does not close"),
    "few-samples": (_text(points=10, rows=_rows(10)), r"10 samples; at least 50 are needed"),
    "nul": (_text(header=("SOURCE lab\0",)), r"line 1: a NUL byte: binary data, not an ASTM E1392 text file"),
    "long-line": (_text(header=("SOURCE " + "x" * MAX_LINE,)), r"line 1: longer than 131,072 characters"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_a_malformed_file_is_refused_naming_its_line(tmp_path, case):
    text, message = MALFORMED[case]
    path = tmp_path / f"{case}.astm"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}: {message}"):
        read_samples(path)


def test_binary_junk_is_refused_as_not_text(tmp_path):
    path = tmp_path / "junk.astm"
    for junk in (bytes(range(256)) * 8, b"NUM_POINTS 60\n" + bytes(range(128, 256)) * 8):
        path.write_bytes(junk)
        with pytest.raises(ValueError, match=r"junk\.astm: not UTF-8 text \(the byte b'\\x80' is not UTF-8\): not an "
                                             r"ASTM E1392 file"):
            read_samples(path)
    path.write_bytes(b"\0" * 4096)
    with pytest.raises(ValueError, match=r"junk\.astm: line 1: a NUL byte: binary data, not an ASTM E1392 text file"):
        read_samples(path)


def test_the_size_and_the_rows_are_bounded(tmp_path, monkeypatch):
    path = tmp_path / "big.astm"
    path.write_text(_text(points=61, rows=_rows(61)))
    monkeypatch.setattr(astm_module, "MAX_SAMPLES", 60)
    with pytest.raises(ValueError, match=r"line 2: NUM_POINTS says 61 samples; give at most 60"):
        read_samples(path)
    path.write_text(_text(points=60, rows=_rows(61)))  # NUM_POINTS within the bound, the rows beyond it
    with pytest.raises(ValueError, match=r"big\.astm: more than 60 samples; give at most that many"):
        read_samples(path)
    monkeypatch.setattr(astm_module, "MAX_BYTES", 1000)
    with pytest.raises(ValueError, match=r"big\.astm: [\d,]+ bytes; an ASTM file of at most 60 samples takes at most "
                                         r"1,000"):
        read_samples(path)
