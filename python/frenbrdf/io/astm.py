"""ASTM E1392 files (``.astm``): angle-resolved scatter data, as gonioreflectometers export it and Disney's BRDF
Explorer reads it, read into :class:`~frenbrdf.io.samples.Measurements` and written from it.

The format
    Text, one keyword line each in a header (``KEYWORD value``), then one row of numbers per measured
    configuration::

        SOURCE goniometer-7
        SAMPLE_NAME "blue paint"
        SCATTER_TYPE BRDF
        NUM_POINTS 1439
        VARS theta_i,phi_i,theta_s,phi_s,R,G,B
        0.1745329,0,0.1745329,3.1415927,0.81,0.42,0.17
        ...

    ``VARS`` names the columns: ``theta_i, phi_i, theta_s, phi_s`` (any case), then ``R,G,B`` or one value column
    (``BRDF``, ``Y`` or one wavelength such as ``550nm``). A single value is read as grey: the same value in the
    three channels. ``NUM_POINTS`` is the number of rows. Other keywords (``DATE``, ``WAVELENGTH``,
    ``POLARIZATION``, ``FORMAT``, …) are accepted and ignored; ``SCATTER_TYPE``, where given, must be ``BRDF``.
    Lines starting with ``#`` and blank lines are skipped anywhere. A row's numbers are separated by commas
    (spaces around them are fine) or, in a row without commas, by spaces.

Angles and values
    Radians. θ is measured from the surface normal, 0 … π/2; φ is the azimuth, any finite value. Both directions
    point away from the surface (the light's and the viewer's), ω = (sin θ cos φ, sin θ sin φ, cos θ), as the
    angle form of a CSV of samples: the mirror direction of (θ_i, φ_i) is (θ_i, φ_i + π). Values are the BRDF in
    1/sr (not multiplied by cos θ_i).

What is refused
    Every error names the file, and the line (1-based, as an editor shows it) where there is one: a header line
    that is not ``KEYWORD value`` (a quoted value must close its quote); no ``VARS`` or no ``NUM_POINTS`` before
    the rows, or either given twice; ``VARS`` without the four angles first, or with another quantity (``BTDF``,
    spectral or XYZ columns); a ``SCATTER_TYPE`` other than BRDF; ``NUM_POINTS`` other than the number of rows; a
    row with too few or too many values, text where a number goes, NaN or infinity; θ below 0 or above π/2 (angles
    in degrees: *angles must be radians*); text that is not UTF-8, NUL bytes, a line longer than
    :data:`MAX_LINE` characters. Negative values, as measurement noise leaves them, are refused as the CSV reader
    refuses them (:func:`frenbrdf.io.samples.read_csv_samples`): the first such line is named and how many there
    are; nothing is clipped to 0 unasked, which would bias the fit upwards: clip or drop them before. Then the
    checks every file of samples passes: at least :data:`~frenbrdf.io.samples.MIN_SAMPLES` rows, at most
    :data:`~frenbrdf.io.samples.MAX_SAMPLES` (a file is refused at the header when ``NUM_POINTS`` says more, and
    at the first row beyond; a file larger than :data:`MAX_BYTES` before it is read), values at most
    :data:`~frenbrdf.io.reflectance.MAX_REFLECTANCE` 1/sr.

The reader streams the file line by line into one float64 array, as the CSV reader does. The writer writes the
vector form's samples as angles (θ = atan2(√(x² + y²), z), φ = atan2(y, x)) and R,G,B, every number as its
shortest repr, so that values read back exactly and directions to float64's precision; atomically.

Examples
--------
>>> from frenbrdf.io import read_samples, write_samples
>>> samples = read_samples("blue-paint.astm")              # doctest: +SKIP
>>> write_samples("blue-paint.csv", samples)               # doctest: +SKIP
"""

from __future__ import annotations

import array
import itertools
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import TextIO

import numpy as np

from .._native import __version__
from .atomic import atomic_path
from .paths import input_file
from .samples import MAX_SAMPLES, Measurements, _checked, _columns, is_number

#: The suffix of ASTM E1392 files.
SUFFIX = ".astm"
#: The angle columns ``VARS`` must name first, in this order (compared in any case).
ANGLES = ("theta_i", "phi_i", "theta_s", "phi_s")
#: The names of one value column read as grey (compared in any case); a wavelength (``550nm``) is one too.
GREY = ("BRDF", "Y")
#: The longest line read, in characters: the CSV reader's limit on one field (Python's csv module's default).
MAX_LINE = 131_072
#: The largest file read, checked before a line is: :data:`~frenbrdf.io.samples.MAX_SAMPLES` rows of seven numbers
#: at 26 characters each (a float64's longest repr is 24; a comma and a space), and 1 MiB of header and comments.
MAX_BYTES = MAX_SAMPLES * 7 * 26 + (1 << 20)

_KEYWORD = re.compile(r"([A-Za-z][A-Za-z0-9_]*)(?:\s+(.*))?")
_WAVELENGTH = re.compile(r"\d+(\.\d*)?\s*nm", re.IGNORECASE)


def read_astm_samples(path: str | os.PathLike) -> Measurements:
    """Reads an ASTM E1392 file of BRDF samples (see the module docstring): R,G,B columns as they are, one value
    column as grey (the same value in the three channels).

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        No such file, or a folder.
    ValueError
        Anything wrong with the contents (the message names the file and the line), or not a regular file (a FIFO).
    """
    path = input_file(path, "measurement file")
    size = path.stat().st_size
    if size > MAX_BYTES:
        raise ValueError(f"{path}: {size:,} bytes; an ASTM file of at most {MAX_SAMPLES:,} samples takes at most "
                         f"{MAX_BYTES:,}")
    names, data, numbers = _read(path)
    values = np.frombuffer(data, dtype=np.float64).reshape(-1, len(names))
    columns = {name: values[:, i] for i, name in enumerate(names)}
    lines = np.frombuffer(numbers, dtype=np.int64)

    def fail(bad: np.ndarray, what: str):
        first = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{path}: line {lines[first]}: {what} ({int(bad.sum())} such line(s) in all)")

    for name, column in columns.items():
        if not np.all(np.isfinite(column)):
            fail(~np.isfinite(column), f"{name} is NaN or infinite")
    for name in (names[0], names[2]):
        theta = columns[name]
        if theta.min() < 0:
            fail(theta < 0, f"{name} is {theta[theta < 0][0]:.6g}, negative: θ is measured from the normal, "
                            "0 … π/2")
        if theta.max() > np.pi / 2:
            above = theta > np.pi / 2
            fail(above, f"{name} is {theta[above][0]:.6g}, above π/2 ({np.pi / 2:.6g}): angles must be radians, θ "
                        "from the normal in 0 … π/2 (is the file in degrees?)")
    for name in names[4:]:
        if columns[name].min() < 0:  # as the CSV reader: refused, never clipped
            negative = columns[name] < 0
            fail(negative, f"{name} is {columns[name][negative][0]:.6g}, negative (BRDF values must be ≥ 0: "
                           "clip or drop the noise below 0 before)")
    vectors = {}
    for d, (polar, azimuth) in (("wi", names[:2]), ("wo", names[2:4])):
        theta, phi = columns[polar], columns[azimuth]
        sin = np.sin(theta)
        vectors.update({f"{d}_x": sin * np.cos(phi), f"{d}_y": sin * np.sin(phi), f"{d}_z": np.cos(theta)})
    colours = names[4:] if len(names) == 7 else names[4:] * 3  # one value: grey
    vectors.update({c: columns[name] for c, name in zip("rgb", colours, strict=True)})
    return _checked(path, "astm", vectors, lines, unit="line")


def write_astm_samples(path: str | os.PathLike, measurements: Measurements, *, sample_name: str | None = None) -> None:
    """Writes samples as an ASTM E1392 file, atomically: a header (``SOURCE``, ``SAMPLE_NAME`` — ``sample_name``,
    else the file's stem —, ``SCATTER_TYPE BRDF``, ``NUM_POINTS``, ``VARS theta_i,phi_i,theta_s,phi_s,R,G,B``),
    then one row per sample, angles in radians, every number as its shortest repr (values read back exactly)."""
    columns = _columns(path, measurements)
    wi, wo = (np.stack([columns[f"{d}_{axis}"] for axis in "xyz"], axis=-1) for d in ("wi", "wo"))
    rows = np.stack([*_angles(wi), *_angles(wo), columns["r"], columns["g"], columns["b"]], axis=1)
    name = _quoted(Path(path).stem if sample_name is None else sample_name)
    header = [f"SOURCE frenbrdf {__version__}", f"SAMPLE_NAME {name}", "SCATTER_TYPE BRDF",
              f"NUM_POINTS {len(rows)}", f"VARS {','.join(ANGLES)},R,G,B"]
    with atomic_path(path) as temporary, open(temporary, "w", encoding="utf-8", newline="\n") as file:
        file.write("\n".join(header) + "\n")
        for start in range(0, len(rows), 1 << 16):  # in chunks: the text of 4 M rows need not be held at once
            file.writelines(",".join(map(repr, row)) + "\n" for row in rows[start:start + (1 << 16)].tolist())


def _angles(directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) of unit directions ``(N, 3)``: atan2 keeps θ exact near the normal, where arccos(z) loses digits."""
    x, y, z = directions.T
    return np.arctan2(np.hypot(x, y), z), np.arctan2(y, x)


def _quoted(name: str) -> str:
    """A sample name as a header value: quoted, one line, no quote inside."""
    return '"' + re.sub(r"[\x00-\x1f\x7f\"]", "_", name) + '"'


def _lines(file: TextIO, path: Path) -> Iterator[tuple[int, str]]:
    """The file's lines, numbered from 1, each at most :data:`MAX_LINE` characters."""
    for number in itertools.count(1):
        line = file.readline(MAX_LINE + 1)
        if not line:
            return
        if len(line) > MAX_LINE and not line.endswith("\n"):
            raise ValueError(f"{path}: line {number}: longer than {MAX_LINE:,} characters; not an ASTM E1392 file")
        if "\0" in line:
            raise ValueError(f"{path}: line {number}: a NUL byte: binary data, not an ASTM E1392 text file")
        yield number, line.strip()


def _cells(line: str) -> list[str]:
    return line.split(",") if "," in line else line.split()


def _read(path: Path) -> tuple[list[str], array.array, array.array]:
    """The column names (``VARS``), the rows' numbers in one flat float64 buffer, and the line of each row."""
    data, rows = array.array("d"), array.array("q")
    header: dict[str, tuple[int, str]] = {}  # the keywords frenbrdf reads: (line, value)
    names: list[str] | None = None
    content = False  # any line but blank ones
    try:
        with open(path, encoding="utf-8-sig", newline=None) as file:
            for number, line in _lines(file, path):
                content = content or bool(line)
                if not line or line.startswith("#"):
                    continue
                cells = _cells(line)
                if names is None and not is_number(cells[0]):
                    _keyword(path, number, line, header)
                    continue
                if names is None:
                    names = _header(path, number, header)
                if len(cells) != len(names):
                    raise ValueError(f"{path}: line {number}: {len(cells)} values, VARS names {len(names)} "
                                     f"columns ({','.join(names)})")
                try:
                    data.extend(map(float, cells))
                except ValueError:
                    column = next(i for i, cell in enumerate(cells) if not is_number(cell))
                    raise ValueError(f"{path}: line {number}, column {names[column]}: "
                                     f"{cells[column].strip()[:40]!r} is not a number") from None
                rows.append(number)
                if len(rows) > MAX_SAMPLES:
                    raise ValueError(f"{path}: more than {MAX_SAMPLES:,} samples; give at most that many")
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: not UTF-8 text (the byte {error.object[error.start:error.end]!r} is not UTF-8): "
                         "not an ASTM E1392 file, or one to save as UTF-8 (ASCII is)") from None
    if not content:
        raise ValueError(f"{path}: the file is empty (an ASTM E1392 header and rows of samples are needed)")
    if names is None:
        _header(path, None, header)  # names what the header lacks, if anything
        raise ValueError(f"{path}: no rows of samples after the header (NUM_POINTS says {header['NUM_POINTS'][1]})")
    declared = int(header["NUM_POINTS"][1])
    if declared != len(rows):
        raise ValueError(f"{path}: NUM_POINTS (line {header['NUM_POINTS'][0]}) says {declared:,} rows, the file "
                         f"holds {len(rows):,}{' (cut short?)' if len(rows) < declared else ''}")
    return names, data, rows


def _keyword(path: Path, number: int, line: str, header: dict[str, tuple[int, str]]) -> None:
    """Checks one header line, ``KEYWORD value``; keeps the value of the keywords frenbrdf reads."""
    match = _KEYWORD.fullmatch(line)
    if match is None:
        raise ValueError(f"{path}: line {number}: {line[:60]!r} is neither a header line (KEYWORD value) nor a row "
                         "of numbers")
    keyword, value = match.group(1).upper(), (match.group(2) or "").strip()
    if value.startswith('"') and (len(value) < 2 or not value.endswith('"')):
        raise ValueError(f"{path}: line {number}: {keyword}'s value {value[:60]} opens a quote it does not close")
    if keyword not in ("VARS", "NUM_POINTS", "SCATTER_TYPE"):
        return  # SOURCE, SAMPLE_NAME, DATE, WAVELENGTH, …: accepted, not used
    if keyword in header:
        raise ValueError(f"{path}: line {number}: {keyword} is given twice (first on line {header[keyword][0]})")
    if not value:
        raise ValueError(f"{path}: line {number}: {keyword} without a value")
    if keyword == "NUM_POINTS" and not (value.isascii() and value.isdigit()):
        raise ValueError(f"{path}: line {number}: NUM_POINTS must be a whole number of rows, got {value[:40]!r}")
    if keyword == "NUM_POINTS" and int(value) > MAX_SAMPLES:
        raise ValueError(f"{path}: line {number}: NUM_POINTS says {int(value):,} samples; give at most "
                         f"{MAX_SAMPLES:,}")
    if keyword == "SCATTER_TYPE" and value.strip('"').upper() != "BRDF":
        raise ValueError(f"{path}: line {number}: SCATTER_TYPE {value[:40]}: frenbrdf reads BRDF (reflected light) "
                         "only")
    header[keyword] = (number, value)


def _header(path: Path, number: int | None, header: dict[str, tuple[int, str]]) -> list[str]:
    """The column names of ``VARS``, checked, once the header is whole (``number``: the first row's line)."""
    before = f" before the first row (line {number})" if number is not None else ""
    for keyword, what in (("VARS", "the columns, e.g. VARS theta_i,phi_i,theta_s,phi_s,R,G,B"),
                          ("NUM_POINTS", "the number of rows")):
        if keyword not in header:
            raise ValueError(f"{path}: no {keyword} line{before}: an ASTM E1392 header names {what}")
    line, value = header["VARS"]
    names = [name.strip() for name in _cells(value)]
    where = f"{path}: line {line}: VARS {value[:80]}"
    if [name.lower() for name in names[:4]] != list(ANGLES):
        raise ValueError(f"{where}: the columns must start with the angles {','.join(ANGLES)}")
    values = names[4:]
    if len(set(name.lower() for name in names)) != len(names):
        raise ValueError(f"{where}: a column is named twice")
    if [name.upper() for name in values] == ["R", "G", "B"]:
        return names
    if len(values) == 1 and (values[0].upper() in GREY or _WAVELENGTH.fullmatch(values[0])):
        return names
    if [name.upper() for name in values] == ["X", "Y", "Z"]:
        raise ValueError(f"{where}: CIE XYZ values; frenbrdf reads R,G,B (convert them to linear RGB first)")
    if len(values) > 1 and all(_WAVELENGTH.fullmatch(name) for name in values):
        raise ValueError(f"{where}: {len(values)} wavelengths (spectral data); frenbrdf reads R,G,B or one value "
                         "column")
    raise ValueError(f"{where}: after the angles, frenbrdf reads R,G,B or one BRDF value column "
                     f"({', '.join(GREY)} or a wavelength such as 550nm), got {','.join(values) or 'none'}")

