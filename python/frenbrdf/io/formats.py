"""A material's files: one table of formats, by suffix, and the functions that read and write through it.

===========  ==================================  ==========================  ===============================
suffix       holds                               :func:`read_material`       :func:`read_samples`
===========  ==================================  ==========================  ===============================
``.binary``  a MERL table                        the table (an array)        samples drawn at its bins
``.bsdf``    an RGL measurement                  :class:`MeasuredBSDF`       samples drawn at the MERL bins
``.pt``      an NBRDF saved by frenbrdf          :class:`NBRDFWeights`       —
``.h5``      a published Keras NBRDF             :class:`NBRDFWeights`       —
``.csv``     samples in CSV                      —                           the samples
``.npz``     samples in NPZ                      —                           the samples
``.astm``    ASTM E1392 scatter data             —                           the samples (:mod:`frenbrdf.io.astm`)
===========  ==================================  ==========================  ===============================

Suffixes are matched whatever their case (``GOLD.H5``). :func:`write_material` writes ``.binary`` and ``.pt``,
:func:`write_samples` ``.csv``, ``.npz`` and ``.astm``, each atomically. A suffix of no format, or of a format that
does not hold what is asked for, is refused with one message naming the file and the suffixes accepted.

What :func:`read_material` returns is the file's own content: an NBRDF file gives its weights, as files sit below
the models; :meth:`frenbrdf.NBRDF.from_weights` (or :func:`frenbrdf.models.nbrdf.as_brdf`, which leaves a table or
a measurement as it is) makes the network.

Examples
--------
>>> import frenbrdf
>>> table = frenbrdf.read_material("gold-paint.binary")             # doctest: +SKIP
>>> samples = frenbrdf.read_samples("my-measurements.csv")          # doctest: +SKIP
>>> samples = frenbrdf.read_samples("gold-paint.binary", samples=4000, seed=0)  # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .astm import SUFFIX as ASTM_SUFFIX
from .astm import read_astm_samples, write_astm_samples
from .bsdf import SUFFIX as BSDF_SUFFIX
from .bsdf import MeasuredBSDF, read_bsdf
from .merl import read_merl, write_merl
from .nbrdf import NBRDFWeights, read_nbrdf, write_nbrdf
from .paths import input_file
from .patterns import DEFAULT as DEFAULT_PATTERN
from .patterns import measure
from .patterns import pattern as find_pattern
from .samples import Measurements, read_csv_samples, read_npz_samples, write_csv_samples, write_npz_samples
from .sampling import as_table, draw_samples

#: What :func:`read_material` returns: a MERL table ``(3, 90, 90, 180)`` (``.binary``), a measurement (``.bsdf``),
#: or an NBRDF's weights (``.pt``, ``.h5``).
Material = np.ndarray | MeasuredBSDF | NBRDFWeights


@dataclass(frozen=True)
class Format:
    """One kind of material file: what it holds and the functions that read and write it."""

    suffix: str
    """The suffix, lower case."""
    holds: str
    """What the file holds, for messages."""
    role: str
    """``"measurement"`` (a whole measured material: read whole, or sampled), ``"nbrdf"`` (a network's weights) or
    ``"samples"`` (scattered samples)."""
    read: Callable[[Path], Any]
    """path → the table, the measurement, the weights, or :class:`Measurements`."""
    write: Callable[[str | os.PathLike, Any], None] | None = None
    """(path, what ``read`` returns) → None, atomically; None where frenbrdf writes no such file."""


def _read_keras(path: Path) -> NBRDFWeights:
    from .keras import keras_weights, read_keras_nbrdf  # h5py, imported only when a Keras file is read

    return keras_weights(read_keras_nbrdf(path), source=path)


#: Every format of a material's files, by suffix.
FORMATS = {entry.suffix: entry for entry in (
    Format(".binary", "a MERL table", "measurement", read_merl, write_merl),
    Format(BSDF_SUFFIX, "an RGL measurement", "measurement", read_bsdf),
    Format(".pt", "a saved NBRDF", "nbrdf", read_nbrdf, write_nbrdf),
    Format(".h5", "a published Keras NBRDF", "nbrdf", _read_keras),
    Format(".csv", "samples in CSV", "samples", read_csv_samples, write_csv_samples),
    Format(".npz", "samples in NPZ", "samples", read_npz_samples, write_npz_samples),
    Format(ASTM_SUFFIX, "ASTM E1392 scatter data", "samples", read_astm_samples, write_astm_samples),
)}
#: The suffixes of measured materials, as material folders hold them (:func:`read_table` reads them).
MEASURED = tuple(suffix for suffix, entry in FORMATS.items() if entry.role == "measurement")


def format_of(path: str | os.PathLike, roles: tuple[str, ...], action: str, *, writing: bool = False) -> Format:
    """The format of ``path`` by its suffix (any case), one of ``roles`` (and with a writer when ``writing``).

    Raises
    ------
    ValueError
        No such format, or one that does not hold what ``action`` reads or writes: the message names the file and
        the suffixes accepted.
    """
    suffix = Path(path).suffix.lower()
    entry = FORMATS.get(suffix)
    accepted = [e for e in FORMATS.values() if e.role in roles and (e.write or not writing)]
    if entry in accepted:
        return entry
    listed = ", ".join(f"{e.suffix} ({e.holds})" for e in accepted)
    found = f"is {entry.holds} ({suffix})" if entry else f"has the suffix {suffix!r}" if suffix else "has no suffix"
    raise ValueError(f"{os.fspath(path)}: {action} {'writes' if writing else 'reads'} {listed}; this file {found}")


def read_material(path: str | os.PathLike) -> Material:
    """Reads a whole material: a MERL ``.binary``, an RGL ``.bsdf``, a saved NBRDF ``.pt`` or a Keras NBRDF ``.h5``.

    Returns
    -------
    numpy.ndarray, MeasuredBSDF or NBRDFWeights
        The MERL table ``(3, 90, 90, 180)`` in physical units (missing bins negative); the measurement (callable
        like an NBRDF); or the NBRDF's weights (:meth:`frenbrdf.NBRDF.from_weights` makes the network).

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        ``path`` does not exist, or is a folder.
    ValueError
        Another suffix (:func:`format_of`), or contents that are not of the format (the message names the file).
    """
    path = input_file(path, "material file")  # a folder, FIFO or link loop is named as such, never read
    return format_of(path, ("measurement", "nbrdf"), "read_material").read(path)


def read_measured(path: str | os.PathLike) -> np.ndarray | MeasuredBSDF:
    """A measured material (``.binary``, ``.bsdf``) whole, as :func:`read_material` reads it: the MERL table or the
    measurement; an NBRDF file is refused. Raises as :func:`read_material`."""
    path = input_file(path, "material file")
    return format_of(path, ("measurement",), "read_measured").read(path)


def read_table(path: str | os.PathLike) -> np.ndarray:
    """A measured material (``.binary``, ``.bsdf``) as a MERL table ``(3, 90, 90, 180)``: a ``.bsdf`` evaluated at
    every MERL bin, missing bins negative. Raises as :func:`read_material`."""
    path = input_file(path, "material file")
    return as_table(format_of(path, ("measurement",), "read_table").read(path))


def read_samples(path: str | os.PathLike, *, samples: int | None = 4000, seed: int = 0,
                 pattern: str = DEFAULT_PATTERN) -> Measurements:
    """Reads the samples of one material: a CSV, NPZ or ASTM E1392 (``.astm``) file of samples, or samples drawn
    from a MERL ``.binary`` or an RGL ``.bsdf`` (:func:`frenbrdf.io.sampling.draw_samples`: the whole material is kept as the truth).

    Parameters
    ----------
    path
        The file; its suffix picks the format (:data:`FORMATS`).
    samples
        A whole material only: sample this many random valid MERL bins (from ``seed``), or all of them (None);
        with another ``pattern``, this many of its pairs.
    seed
        A whole material only: seeds the bins drawn (and a measurement's order of each pair), or the pattern.
    pattern
        A whole material only: the sampling pattern, a name of :data:`frenbrdf.io.patterns.PATTERNS` (the device
        imitated); the default, ``merl-bins``, draws random valid MERL bins. Another is measured at its pairs
        (:func:`frenbrdf.io.patterns.measure`).

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        No such file, or a folder.
    ValueError
        Another suffix (:func:`format_of`), anything wrong with the contents (the message names the file and the
        row), or not a regular file (a FIFO).
    """
    path = input_file(path, "measurement file")
    entry = format_of(path, ("samples", "measurement"), "read_samples")
    find_pattern(pattern)  # an unknown pattern is named, whatever the file
    if entry.role == "samples":
        return entry.read(path)
    if pattern == DEFAULT_PATTERN:
        return draw_samples(entry.read(path), samples=samples, seed=seed, source=str(path))
    if samples is None:
        raise ValueError(f"samples=None (all) draws every MERL bin: the {DEFAULT_PATTERN} pattern only, not {pattern!r}")
    return measure(entry.read(path), pattern, samples, np.random.default_rng(seed), source=str(path))


def write_material(path: str | os.PathLike, material: np.ndarray | NBRDFWeights) -> None:
    """Writes a whole material, atomically: a MERL table as a ``.binary``, an NBRDF's weights
    (:meth:`frenbrdf.NBRDF.weights`) as a ``.pt``."""
    entry = format_of(path, ("measurement", "nbrdf"), "write_material", writing=True)
    assert entry.write is not None  # format_of(writing=True) picks only formats with a writer
    entry.write(path, material)


def write_samples(path: str | os.PathLike, measurements: Measurements) -> None:
    """Writes samples as a ``.csv`` or an ``.npz`` (the vector form) or an ``.astm`` (angles), atomically;
    :func:`read_samples` reads them back."""
    entry = format_of(path, ("samples",), "write_samples", writing=True)
    assert entry.write is not None  # format_of(writing=True) picks only formats with a writer
    entry.write(path, measurements)
