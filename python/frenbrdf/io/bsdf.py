"""Real measurements: the RGB ``.bsdf`` files of the RGL material database.

The files hold a gonio-photometer measurement in the adaptive parameterisation of Dupuy &
Jakob 2018 ("An Adaptive Parameterization for Efficient Material Acquisition and Rendering",
ACM TOG 37(6)). The Rust core reads and checks them (``rust/bsdf/``) and evaluates the BRDF
at any direction pairs; :func:`read_bsdf` wraps that in a :class:`MeasuredBSDF`, callable
like a decoded NBRDF, so that every renderer and metric takes a measurement as it is.

Examples
--------
>>> import frenbrdf
>>> paper = frenbrdf.read_bsdf("paper_white_rgb.bsdf")            # doctest: +SKIP
>>> paper(wi, wo).shape                                           # doctest: +SKIP
(1000, 3)
>>> frenbrdf.write_merl("paper_white.binary", paper.table())      # doctest: +SKIP
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._native import BSDF_HORIZON, BsdfMeasurement
from ..exceptions import BsdfFormatError
from ..numerics._arrays import rows
from .merl import TABLE_AXES
from .paths import input_file
from .reflectance import check_reflectance

#: The suffix of the files :func:`read_bsdf` reads.
SUFFIX = ".bsdf"
#: A direction whose z (unit length) is at most this lies at the horizon, where a measurement is 0: pairs on the
#: horizon but for rounding (MERL bins with z = 1e-16) would otherwise be worth 1e14/sr.
HORIZON = BSDF_HORIZON


class MeasuredBSDF:
    """A measured material read from an RGL ``.bsdf`` file (:func:`read_bsdf`).

    Call it as ``m(wi, wo)`` with unit directions ``(..., 3)`` in the local shading frame
    (z = the normal): it returns ``(..., 3)`` RGB reflectance in 1/sr, not multiplied by
    cos θ, with negative measured values clamped to 0 and 0 at and below the horizon (z ≤
    :data:`HORIZON`). The files tabulate f · cos θ_o, which does not vanish at the horizon: f
    grows as 1/cos θ_o over the last degree or two, as Mitsuba's values over cos θ_o do.

    It computes in float32, vectorised across pairs, within about 1e-5 (relative) of the float64
    evaluation that ``double=True`` asks for (several times slower).
    """

    def __init__(self, native: BsdfMeasurement):
        self._native = native

    @property
    def path(self) -> Path:
        """The file read."""
        return Path(self._native.path)

    @property
    def name(self) -> str:
        """The material's name: the file's stem."""
        return self.path.stem

    @property
    def description(self) -> str:
        """The file's own description ('' if it has none)."""
        return self._native.description

    @property
    def isotropic(self) -> bool:
        """Whether the material was measured as isotropic."""
        return self._native.isotropic

    def __call__(self, wi, wo, *, double: bool = False) -> np.ndarray:
        wi_rows, leading = rows("wi", wi, 3)
        wo_rows, leading_o = rows("wo", wo, 3)
        if leading != leading_o:
            raise ValueError(f"wi and wo must have the same shape, got {np.shape(wi)} and {np.shape(wo)}")
        values = self._native.eval(wi_rows, wo_rows, double)
        # Every value the measurement gives is checked as its table's are: a file may hold fields (sigma, the
        # warps) that scale an accepted rgb past any reflectance.
        check_reflectance(values, self.path, what="evaluated values", axes="(pair, channel)", error=BsdfFormatError)
        return values.reshape(*leading, 3)

    def table(self, *, double: bool = False) -> np.ndarray:
        """The measurement at every MERL bin (float32 arithmetic unless ``double``): a table
        ``(3, 90, 90, 180)`` in 1/sr, with the negative "missing" markers of MERL files where a bin's
        directions lie below the horizon."""
        table = self._native.merl_table(double)
        # What trains and reconstructs: the values at the bins, checked as a MERL file's are.
        check_reflectance(table, self.path, what="values at the MERL bins", axes=TABLE_AXES, error=BsdfFormatError)
        return table

    def __repr__(self) -> str:
        return f"MeasuredBSDF({str(self.path)!r}, description={self.description!r})"


def read_bsdf(path: str | os.PathLike) -> MeasuredBSDF:
    """Reads an RGL RGB ``.bsdf`` measurement.

    Raises
    ------
    FileNotFoundError, IsADirectoryError, PermissionError
        The file cannot be opened.
    ValueError
        A FIFO, device or link loop rather than a file.
    frenbrdf.BsdfFormatError
        The file is not a ``tensor_file`` v1.0 RGB BSDF (wrong magic or version, truncated, a field of the wrong
        type or shape or with values outside its domain, declaring more than 256 MiB, a spectral file), or its
        ``rgb`` values are not reflectance (:func:`~frenbrdf.io.reflectance.check_reflectance`); the message
        names the file and what was wrong.
    """
    path = input_file(path, ".bsdf measurement")  # a folder or FIFO is named as such, never read
    native = BsdfMeasurement.read(path)
    # The stored values are f·cos θ_o, divided by D/(4σ) where `jacobian` is set: the RGL files hold at most
    # about 20; one past MAX_REFLECTANCE is no reflectance (and rendering evaluates these values as they are).
    check_reflectance(native.rgb.reshape(native.fields["rgb"][1]), path, what="values of field rgb",
                      axes="(phi_i, theta_i, channel, y, x)", error=BsdfFormatError)
    return MeasuredBSDF(native)
