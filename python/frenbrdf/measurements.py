"""A user's measurements of one material: scattered (ω_i, ω_o, RGB) samples from a file.

Three inputs are read, each into :class:`Measurements`:

CSV (``.csv``)
    A header row, then one sample per row. Either the *vector form*,
    ``wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b``, or an *angle form*,
    ``theta_i,phi_i,theta_o,phi_o,r,g,b`` (radians) or
    ``theta_i_deg,phi_i_deg,theta_o_deg,phi_o_deg,r,g,b`` (degrees), with
    ω = (sin θ cos φ, sin θ sin φ, cos θ). Columns may come in any order; no other columns.
NPZ (``.npz``)
    One 1-D array per column of one of the forms above, named as the columns.
MERL (``.binary``)
    A MERL table sampled at ``samples`` random valid bins (default 4000) or at all of them;
    the table is kept as the truth.

Directions are unit vectors in the local shading frame (z = the surface normal, both above
the surface: z > 0). Lengths may be off by at most :data:`UNIT_TOLERANCE` (1e-3); they are
then normalised. ``r, g, b`` is the BRDF value in 1/sr (reflectance as MERL tables hold it
in physical units, not multiplied by cos θ_i), ≥ 0, finite. At least :data:`MIN_SAMPLES`
samples. Every error names the file and the row, 1-based as a spreadsheet shows it (the
CSV header is row 1; in an NPZ, row k is the k-th sample).
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: The fewest samples accepted: fewer say too little about a material for the encoder.
MIN_SAMPLES = 50
#: How far from 1 a direction's length may be (it is then normalised).
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
    """Samples of one material."""

    values: np.ndarray
    """``(N, 3)`` float64 BRDF values (1/sr), ≥ 0."""
    wi: np.ndarray
    """``(N, 3)`` unit incident directions, local frame, z > 0."""
    wo: np.ndarray
    """``(N, 3)`` unit outgoing directions."""
    source: str
    """The file read."""
    kind: str
    """``"csv"``, ``"npz"`` or ``"merl"``."""
    table: np.ndarray | None = None
    """The whole MERL table ``(3, 90, 90, 180)`` when the input was one (the truth), else None."""

    def __len__(self) -> int:
        return len(self.values)


def read_measurements(path: str | os.PathLike, *, samples: int | None = 4000, seed: int = 0) -> Measurements:
    """Reads a CSV, NPZ or MERL file (see the module docstring).

    Parameters
    ----------
    path
        The file; its suffix picks the format (a MERL file may also be recognised by its size).
    samples
        MERL input only: sample this many random valid bins (from ``seed``), or all of them (None).

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        Anything wrong with the contents; the message names the file and the row.
    """
    from .merl import FILE_BYTES

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"measurement file {path} does not exist")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        return _checked(path, "csv", *_read_csv(path))
    if suffix == ".npz":
        return _checked(path, "npz", *_read_npz(path))
    if suffix == ".binary" or path.stat().st_size == FILE_BYTES:
        return merl_measurements(path, samples=samples, seed=seed)
    raise ValueError(f"{path}: unknown measurement format; give a .csv or .npz of samples "
                     f"(columns {','.join(FORMS['vectors'])}) or a MERL .binary file")


def merl_measurements(path: str | os.PathLike, *, samples: int | None = 4000, seed: int = 0) -> Measurements:
    """A MERL file sampled at ``samples`` random valid bins (drawn from ``seed``) or at all of them (None)."""
    from .merl import N_BINS, read_merl
    from .scoring import bin_directions, sample_bins

    table = read_merl(path)
    flat = table.reshape(3, N_BINS)
    if samples is None:
        bins = np.flatnonzero(np.all(flat >= 0, axis=0))
    elif samples < 1:
        raise ValueError(f"samples must be ≥ 1 or all, got {samples}")
    else:
        bins = sample_bins(table, np.random.default_rng(seed), samples)
    if len(bins) == 0:
        raise ValueError(f"{path}: the MERL table holds no valid bin")
    wi, wo = bin_directions(bins)
    return Measurements(flat[:, bins].T.copy(), wi, wo, str(path), "merl", table)


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
    """The columns of a CSV file by name, and the (1-based) row number of each sample."""
    with open(path, newline="", encoding="utf-8-sig") as file:
        lines = [(reader_row, number) for number, reader_row in enumerate(csv.reader(file), start=1)
                 if any(cell.strip() for cell in reader_row)]
    if not lines:
        raise ValueError(f"{path}: the file is empty (a header row and samples are needed)")
    header = [cell.strip() for cell in lines[0][0]]
    if any(_is_number(cell) for cell in header):
        raise ValueError(f"{path}: row {lines[0][1]} must be a header naming the columns, "
                         f"e.g. {','.join(FORMS['vectors'])}")
    if len(set(header)) != len(header):
        raise ValueError(f"{path}: row {lines[0][1]}: a column is named twice: {header}")
    _form(header, f"{path}: row {lines[0][1]} (header)")
    data, rows = np.empty((len(lines) - 1, len(header))), np.empty(len(lines) - 1, dtype=np.int64)
    for index, (cells, number) in enumerate(lines[1:]):
        if len(cells) != len(header):
            raise ValueError(f"{path}: row {number}: {len(cells)} values, the header names {len(header)} columns")
        for column, cell in enumerate(cells):
            try:
                data[index, column] = float(cell)
            except ValueError:
                raise ValueError(f"{path}: row {number}, column {header[column]}: {cell.strip()!r} is not a number") \
                    from None
        rows[index] = number
    return {name: data[:, column] for column, name in enumerate(header)}, rows


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _read_npz(path: Path) -> tuple[dict[str, np.ndarray], np.ndarray]:
    try:
        with np.load(path, allow_pickle=False) as saved:
            columns = {name: np.asarray(saved[name]) for name in saved.files}
    except Exception as error:  # numpy raises several types for damaged files
        raise ValueError(f"{path}: not a readable .npz file ({error})") from None
    _form(list(columns), str(path))
    lengths = {name: array.shape for name, array in columns.items()}
    if any(len(shape) != 1 for shape in lengths.values()) or len(set(lengths.values())) != 1:
        raise ValueError(f"{path}: every array must be 1-D with one entry per sample, got shapes {lengths}")
    try:
        columns = {name: array.astype(np.float64) for name, array in columns.items()}
    except (TypeError, ValueError):
        raise ValueError(f"{path}: the arrays must be numbers, got dtypes "
                         f"{ {name: str(a.dtype) for name, a in columns.items()} }") from None
    return columns, np.arange(1, len(next(iter(columns.values()))) + 1)


def _directions(columns: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    if "wi_x" in columns:
        return (np.stack([columns[f"{d}_{axis}"] for axis in "xyz"], axis=-1) for d in ("wi", "wo"))
    suffix, scale = ("_deg", np.pi / 180) if "theta_i_deg" in columns else ("", 1.0)
    out = []
    for d in ("i", "o"):
        theta, phi = columns[f"theta_{d}{suffix}"] * scale, columns[f"phi_{d}{suffix}"] * scale
        out.append(np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1))
    return out[0], out[1]


def _checked(path: Path, kind: str, columns: dict[str, np.ndarray], rows: np.ndarray) -> Measurements:
    """Checks every sample, naming the first bad row; returns the samples with unit directions."""
    def fail(bad: np.ndarray, what: str):
        first = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{path}: row {rows[first]}: {what} ({int(bad.sum())} such row(s) in all)")

    if len(rows) < MIN_SAMPLES:
        raise ValueError(f"{path}: {len(rows)} samples; at least {MIN_SAMPLES} are needed")
    for name, column in columns.items():
        if not np.all(np.isfinite(column)):
            fail(~np.isfinite(column), f"column {name} is NaN or infinite")
    values = np.stack([columns[c] for c in COLOURS], axis=-1)
    if values.min() < 0:
        fail(np.any(values < 0, axis=1), "negative reflectance (r, g, b must be ≥ 0)")
    wi, wo = _directions(columns)
    for name, d in (("ω_i", wi), ("ω_o", wo)):
        length = np.linalg.norm(d, axis=-1)
        off = np.abs(length - 1) > UNIT_TOLERANCE
        if off.any():
            fail(off, f"{name} has length {length[off][0]:.6g}, not a unit vector (tolerance {UNIT_TOLERANCE:g})")
        below = d[:, 2] <= 0
        if below.any():
            fail(below, f"{name} is at or below the horizon (z = {d[below][0, 2]:.6g} ≤ 0; directions are in "
                        "the local shading frame, z = the normal)")
    return Measurements(values, wi / np.linalg.norm(wi, axis=-1, keepdims=True),
                        wo / np.linalg.norm(wo, axis=-1, keepdims=True), str(path), kind)
