"""Measured materials in either format: MERL ``.binary`` tables and RGL ``.bsdf`` measurements.

Material folders may mix both. Every command reads them through two functions:

- :func:`read_table`: the material as a MERL table ``(3, 90, 90, 180)`` (a ``.bsdf`` evaluated
  at the MERL bins, missing bins negative): what training samples and L_fre compares;
- :func:`read_truth`: what is rendered as the truth: the table, or for a ``.bsdf`` the
  measurement itself, evaluated at the renderer's own directions rather than through a
  quantised table.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .bsdf import SUFFIX as BSDF_SUFFIX
from .bsdf import MeasuredBSDF, read_bsdf
from .merl import read_merl

#: The suffixes of measured material files, as material folders hold them.
SUFFIXES = (".binary", BSDF_SUFFIX)


def is_bsdf(path: str | os.PathLike) -> bool:
    """Whether ``path`` names an RGL ``.bsdf`` measurement (by its suffix)."""
    return Path(path).suffix.lower() == BSDF_SUFFIX


def read_truth(path: str | os.PathLike) -> np.ndarray | MeasuredBSDF:
    """A MERL table, or the :class:`MeasuredBSDF` of a ``.bsdf`` file: the truth to render."""
    return read_bsdf(path) if is_bsdf(path) else read_merl(path)


def read_table(path: str | os.PathLike) -> np.ndarray:
    """A MERL file, or a ``.bsdf`` measurement evaluated at every MERL bin: ``(3, 90, 90, 180)``."""
    return as_table(read_truth(path))


def as_table(truth: np.ndarray | MeasuredBSDF) -> np.ndarray:
    """The table of what :func:`read_truth` returned."""
    return truth.table() if isinstance(truth, MeasuredBSDF) else truth
