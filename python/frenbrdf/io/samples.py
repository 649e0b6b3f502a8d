"""Files of samples: a user's measurements of one material, scattered (ω_i, ω_o, RGB) samples.

Two formats are read into :class:`Measurements` and written from it (:func:`frenbrdf.io.read_samples` and
:func:`frenbrdf.io.write_samples` pick one by the suffix; a whole material file is sampled by
:func:`frenbrdf.io.sampling.draw_samples`):

CSV (``.csv``)
    A header row, then one sample per row. Either the *vector form*,
    ``wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b``, or an *angle form*,
    ``theta_i,phi_i,theta_o,phi_o,r,g,b`` (radians) or
    ``theta_i_deg,phi_i_deg,theta_o_deg,phi_o_deg,r,g,b`` (degrees), with
    ω = (sin θ cos φ, sin θ sin φ, cos θ). Columns may come in any order; no other columns.
NPZ (``.npz``)
    One 1-D array per column of one of the forms above, named as the columns.

ASTM E1392 files (``.astm``), as gonioreflectometers export them, are read into the same class and checked the same
way by :mod:`frenbrdf.io.astm`.

Directions are unit vectors in the local shading frame (z = the surface normal, both above
the surface: z > 0). Lengths may be off by at most :data:`UNIT_TOLERANCE` (1e-3); they are
then normalised. ``r, g, b`` is the BRDF value in 1/sr (reflectance as MERL tables hold it
in physical units, not multiplied by cos θ_i), ≥ 0, finite. At least :data:`MIN_SAMPLES`
samples, at most :data:`MAX_SAMPLES`. Every error names the file and the row, 1-based as a
spreadsheet shows it (the CSV header is row 1; in an NPZ, row k is the k-th sample).

A CSV is read row by row into one float64 array (memory about 8 bytes a value, the data's own
size); an NPZ's declared sizes are checked before it is decompressed. Both are written in the vector form,
atomically (a CSV's floats exactly: the shortest repr that reads back as the same number).
"""

from __future__ import annotations

import array
import csv
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import atomic_path, save_csv
from .paths import checked_npz, input_file
from .reflectance import MAX_REFLECTANCE

#: The fewest samples accepted: fewer say too little about a material for the encoder.
MIN_SAMPLES = 50
#: The most samples accepted (a MERL table holds 1.1 million). ``frenbrdf reconstruct`` holds each sample several
#: times over (the values and directions, their NBRDF inputs and mapped values in float64 and float32, the refined
#: NBRDF's copy): about 330 bytes a sample with ``--refine none`` and 540 with ``full``. At this many its measured
#: peak is about 3 GB; a CSV is refused while it is read, at the first row beyond.
MAX_SAMPLES = 4_000_000
#: How far from 1 the length of a given direction may be (it is then normalised); the models check arrays with it.
UNIT_TOLERANCE = 1e-3
#: The column names of each form, and the colour columns they share.
COLOURS = ("r", "g", "b")
FORMS = {
    "vectors": ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z", *COLOURS),
    "radians": ("theta_i", "phi_i", "theta_o", "phi_o", *COLOURS),
    "degrees": ("theta_i_deg", "phi_i_deg", "theta_o_deg", "phi_o_deg", *COLOURS),
}


@dataclass
class Measurements:
    """Samples of one material: what :func:`frenbrdf.io.read_samples` returns and ``reconstruct`` is given."""

    values: np.ndarray
    """``(N, 3)`` float64 BRDF values (1/sr), ≥ 0."""
    wi: np.ndarray
    """``(N, 3)`` unit incident directions, local frame, z > 0."""
    wo: np.ndarray
    """``(N, 3)`` unit outgoing directions."""
    source: str = ""
    """The file read ('' for samples made in memory)."""
    kind: str = "arrays"
    """``"csv"``, ``"npz"``, ``"astm"``, ``"merl"`` or ``"bsdf"``: the format read (``"arrays"``: made in memory)."""
    table: np.ndarray | None = None
    """The whole MERL table ``(3, 90, 90, 180)`` when the input was one (or a ``.bsdf`` at every bin), else None."""
    truth: object = None
    """What renders as the truth: the MERL table, or the :class:`frenbrdf.io.bsdf.MeasuredBSDF` itself; None for
    scattered samples."""

    def __len__(self) -> int:
        return len(self.values)


def read_csv_samples(path: str | os.PathLike) -> Measurements:
    """Reads a CSV of samples (see the module docstring).

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        No such file, or a folder.
    ValueError
        Anything wrong with the contents (the message names the file and the row), or not a regular file
        (a FIFO).
    """
    path = input_file(path, "measurement file")
    return _checked(path, "csv", *_read_csv(path))


def read_npz_samples(path: str | os.PathLike) -> Measurements:
    """Reads an NPZ of samples (see the module docstring); raises as :func:`read_csv_samples`."""
    path = input_file(path, "measurement file")
    return _checked(path, "npz", *_read_npz(path))


def write_csv_samples(path: str | os.PathLike, measurements: Measurements) -> None:
    """Writes samples as a CSV in the vector form, atomically; every float exactly (its shortest round-trip repr)."""
    columns = _columns(path, measurements)
    save_csv(path, [dict(zip(columns, row, strict=True)) for row in np.stack(list(columns.values()), axis=1).tolist()])


def write_npz_samples(path: str | os.PathLike, measurements: Measurements) -> None:
    """Writes samples as an NPZ in the vector form (one float64 array per column), atomically."""
    columns: dict[str, Any] = _columns(path, measurements)  # Any: numpy's stubs take any ** key for allow_pickle
    with atomic_path(path) as temporary, open(temporary, "wb") as file:
        np.savez(file, **columns)


def _columns(path: str | os.PathLike, measurements: Measurements) -> dict[str, np.ndarray]:
    """The columns of the vector form, by name."""
    if not isinstance(measurements, Measurements):
        raise TypeError(f"{os.fspath(path)}: a file of samples holds Measurements, got {type(measurements).__name__}")
    stacked = np.concatenate([np.asarray(a, dtype=np.float64).reshape(-1, 3)
                              for a in (measurements.wi, measurements.wo, measurements.values)], axis=1)
    return dict(zip(FORMS["vectors"], stacked.T, strict=True))


def _form(columns, where: str) -> str:
    """Which form a set of column names is, or a ValueError naming what is missing or extra."""
    for form, names in FORMS.items():
        if set(columns) == set(names) and len(columns) == len(names):
            return form
    best = min(FORMS, key=lambda form: len(set(FORMS[form]) ^ set(columns)))
    missing = [name for name in FORMS[best] if name not in columns]
    extra = [name for name in columns if name not in FORMS[best]]
    raise ValueError(f"{where}: the columns must be {','.join(FORMS['vectors'])} (or an angle form: "
                     f"{','.join(FORMS['radians'])} in radians, {','.join(FORMS['degrees'])} in degrees); "
                     f"missing {missing}, unexpected {extra}")


def _read_csv(path: Path) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The columns of a CSV file by name, and the (1-based) row number of each sample.

    Streamed: each row is parsed as it is read into one flat float64 buffer, so memory stays near the
    data's own size (8 bytes a value) whatever the file's length."""
    data, rows = array.array("d"), array.array("q")
    header, number = None, 0
    try:
        with open(path, newline="", encoding="utf-8-sig") as file:
            for number, cells in enumerate(csv.reader(file), start=1):
                if not any(cell.strip() for cell in cells):
                    continue
                if header is None:
                    header = _header(path, cells, number)
                    continue
                if len(cells) != len(header):
                    raise ValueError(f"{path}: row {number}: {len(cells)} values, the header names {len(header)} "
                                     "columns")
                try:
                    data.extend(map(float, cells))
                except ValueError:
                    column = next(i for i, cell in enumerate(cells) if not is_number(cell))
                    raise ValueError(f"{path}: row {number}, column {header[column]}: {cells[column].strip()[:40]!r} "
                                     "is not a number") from None
                rows.append(number)
                if len(rows) > MAX_SAMPLES:
                    raise ValueError(f"{path}: more than {MAX_SAMPLES:,} samples; give at most that many")
    except csv.Error as error:  # a field beyond csv's limit (131,072 characters), a NUL byte, …
        raise ValueError(f"{path}: row {number + 1}: not readable as CSV ({error})") from None
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: not UTF-8 text (the byte {error.object[error.start:error.end]!r} is not UTF-8); "
                         "save the file as UTF-8 CSV") from None
    if header is None:
        raise ValueError(f"{path}: the file is empty (a header row and samples are needed)")
    values = np.frombuffer(data, dtype=np.float64).reshape(-1, len(header))
    return {name: values[:, column] for column, name in enumerate(header)}, np.frombuffer(rows, dtype=np.int64)


def _header(path: Path, cells: list[str], number: int) -> list[str]:
    """The column names of a CSV's first row, checked."""
    header = [cell.strip() for cell in cells]
    if any(is_number(cell) for cell in header):
        raise ValueError(f"{path}: row {number} must be a header naming the columns, "
                         f"e.g. {','.join(FORMS['vectors'])}")
    if len(set(header)) != len(header):
        raise ValueError(f"{path}: row {number}: a column is named twice: {header}")
    _form(header, f"{path}: row {number} (header)")
    return header


def is_number(text: str) -> bool:
    """Whether ``float()`` reads ``text`` (a header cell is a name, a data cell a number)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _read_npz(path: Path) -> tuple[dict[str, np.ndarray], np.ndarray]:
    # The declared sizes are checked before anything is decompressed (a zip bomb declares gigabytes).
    columns = checked_npz(path, ".npz file of samples", member_bytes=MAX_SAMPLES * 8 + 4096, members=len(FORMS["vectors"]))
    _form(list(columns), str(path))
    lengths = {name: array.shape for name, array in columns.items()}
    if any(len(shape) != 1 for shape in lengths.values()) or len(set(lengths.values())) != 1:
        raise ValueError(f"{path}: every array must be 1-D with one entry per sample, got shapes {lengths}")
    # Real numbers only: numpy would turn text into numbers, drop an imaginary part, and read booleans, dates or
    # records as numbers without a word.
    for name, values in columns.items():
        if values.dtype.kind not in "iuf":
            raise ValueError(f"{path}: array {name} holds {values.dtype} values; the arrays must be real numbers "
                             "(integer or floating point)")
    columns = {name: array.astype(np.float64) for name, array in columns.items()}
    return columns, np.arange(1, len(next(iter(columns.values()))) + 1)


def _directions(columns: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    if "wi_x" in columns:
        wi, wo = (np.stack([columns[f"{d}_{axis}"] for axis in "xyz"], axis=-1) for d in ("wi", "wo"))
        return wi, wo
    suffix, scale = ("_deg", np.pi / 180) if "theta_i_deg" in columns else ("", 1.0)
    out = []
    for d in ("i", "o"):
        theta, phi = columns[f"theta_{d}{suffix}"] * scale, columns[f"phi_{d}{suffix}"] * scale
        out.append(np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1))
    return out[0], out[1]


def _checked(path: Path, kind: str, columns: dict[str, np.ndarray], rows: np.ndarray, *,
             unit: str = "row") -> Measurements:
    """Checks every sample, naming the first bad row (``unit``: what ``rows`` number, ``"line"`` in a file whose
    rows are lines of their own kind); returns the samples with unit directions."""
    def fail(bad: np.ndarray, what: str):
        first = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{path}: {unit} {rows[first]}: {what} ({int(bad.sum())} such {unit}(s) in all)")

    if len(rows) < MIN_SAMPLES:
        raise ValueError(f"{path}: {len(rows)} samples; at least {MIN_SAMPLES} are needed")
    if len(rows) > MAX_SAMPLES:
        raise ValueError(f"{path}: {len(rows):,} samples; give at most {MAX_SAMPLES:,}")
    for name, column_values in columns.items():
        if not np.all(np.isfinite(column_values)):
            fail(~np.isfinite(column_values), f"column {name} is NaN or infinite")
    values = np.stack([columns[c] for c in COLOURS], axis=-1)
    if values.min() < 0:
        fail(np.any(values < 0, axis=1), "negative reflectance (r, g, b must be ≥ 0)")
    if values.max() > MAX_REFLECTANCE:
        fail(np.any(values > MAX_REFLECTANCE, axis=1), f"reflectance above {MAX_REFLECTANCE:g} 1/sr (MERL's highest "
             "spikes are about 1e5; is the unit right?)")
    for column, top, angle_unit in (("theta_i", np.pi / 2, " rad"), ("theta_o", np.pi / 2, " rad"),
                                    ("theta_i_deg", 90.0, "°"), ("theta_o_deg", 90.0, "°")):
        # θ is measured from the normal: 0 ≤ θ < 90° (angles in the wrong unit would wrap round without a word)
        outside = (columns[column] < 0) | (columns[column] >= top) if column in columns else None
        if outside is not None and outside.any():
            hint = "; angles in degrees go in columns named theta_i_deg, …" if angle_unit == " rad" else ""
            fail(outside, f"{column} is {columns[column][outside][0]:.6g}, outside 0 … {top:.6g}{angle_unit} "
                          f"(above the surface{hint})")
    wi, wo = _directions(columns)
    for name, d in (("ω_i", wi), ("ω_o", wo)):
        length = np.sqrt(np.einsum("ij,ij->i", d, d))  # no (N, 3) temporary: memory stays near the data's
        off = np.abs(length - 1) > UNIT_TOLERANCE
        if off.any():
            fail(off, f"{name} has length {length[off][0]:.6g}, not a unit vector (tolerance {UNIT_TOLERANCE:g})")
        below = d[:, 2] <= 0
        if below.any():
            fail(below, f"{name} is at or below the horizon (z = {d[below][0, 2]:.6g} ≤ 0; directions are in "
                        "the local shading frame, z = the normal)")
        d /= length[:, None]  # in place: these arrays are this function's own
    return Measurements(values, wi, wo, str(path), kind)
