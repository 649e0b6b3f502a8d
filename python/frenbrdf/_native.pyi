"""Type stubs for the private native module. Use the public API in `frenbrdf`."""

import os
from pathlib import Path
from typing import TypeAlias, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "__version__", "num_threads", "read_merl", "write_merl", "merl_lookup", "merl_lookup_directions",
    "CHANNEL_SCALES", "FILE_BYTES", "directions_to_rusinkiewicz", "rusinkiewicz_to_directions", "half_diff_vectors",
    "rusinkiewicz_to_half_diff", "merl_bin_to_angles", "merl_angles_to_bin", "KnnInterpolator", "ShtPlan",
    "BsdfMeasurement", "BSDF_HORIZON", "WeightFit",
]

__version__: str
CHANNEL_SCALES: list[float]
FILE_BYTES: int
BSDF_HORIZON: float

# Stub-only aliases (private: the extension has no such names).
_F64: TypeAlias = npt.NDArray[np.float64]
_I64: TypeAlias = npt.NDArray[np.int64]
_F32: TypeAlias = npt.NDArray[np.float32]

def num_threads() -> int: ...

# MERL I/O and lookup
def read_merl(path: str | os.PathLike[str], physical_units: bool = True) -> _F64: ...
def write_merl(path: str | os.PathLike[str], table: _F64, physical_units: bool = True) -> None: ...
def merl_lookup(table: _F64, angles: _F64, method: str) -> _F64: ...
def merl_lookup_directions(table: _F64, wi: _F64, wo: _F64, method: str) -> _F64: ...
def merl_bin_to_angles(bins: _F64) -> _F64: ...
def merl_angles_to_bin(angles: _F64) -> _I64: ...

# Coordinates
def directions_to_rusinkiewicz(wi: _F64, wo: _F64) -> _F64: ...
def rusinkiewicz_to_directions(angles: _F64) -> tuple[_F64, _F64]: ...
def half_diff_vectors(wi: _F64, wo: _F64) -> tuple[_F64, _F64]: ...
def rusinkiewicz_to_half_diff(angles: _F64) -> tuple[_F64, _F64]: ...

# kNN interpolation
@final
class KnnInterpolator:
    def __new__(cls, src: _F64, dst: _F64, k: int, sigma: float) -> KnnInterpolator: ...
    def apply(self, values: _F64) -> _F64: ...
    @property
    def k(self) -> int: ...
    @property
    def n_src(self) -> int: ...
    @property
    def n_dst(self) -> int: ...
    @property
    def indices(self) -> _I64: ...
    @property
    def weights(self) -> _F64: ...

# Spherical harmonic transform (arrays are 2-D: (batch, nlat·nlon) or (batch, (lmax+1)²))
@final
class ShtPlan:
    def __new__(cls, nlat: int, nlon: int, lmax: int, grid: str, dtype: str) -> ShtPlan: ...
    def analysis(self, maps: npt.NDArray[np.floating]) -> npt.NDArray[np.floating]: ...
    def synthesis(self, coeffs: npt.NDArray[np.floating]) -> npt.NDArray[np.floating]: ...
    def analysis_adjoint(self, coeffs: npt.NDArray[np.floating]) -> npt.NDArray[np.floating]: ...
    def degrees_orders(self) -> _I64: ...
    def rings(self) -> tuple[_F64, _F64]: ...

# RGL measured BRDFs (`tensor_file` .bsdf, Dupuy & Jakob 2018)
@final
class BsdfMeasurement:
    """A measured RGB BRDF of the RGL material database (an ``*_rgb.bsdf`` file), ready to evaluate."""

    @staticmethod
    def read(path: str | os.PathLike[str]) -> BsdfMeasurement:
        """Reads and checks a ``.bsdf`` file.

        Raises ``FileNotFoundError`` (and other ``OSError``) for the file system, and
        ``frenbrdf.exceptions.BsdfFormatError`` for a malformed file or a spectral one
        (only RGB files, with an ``rgb`` tensor, are supported).
        """
    def eval(self, wi: _F64, wo: _F64, double: bool = False) -> _F64:
        """The BRDF at ``(n, 3)`` direction pairs (float64, C-contiguous, local frame with z the
        normal; normalised here): ``(n, 3)`` RGB reflectance in 1/sr, not multiplied by cos θ_o,
        negative measurements clamped to 0, and 0 where either direction is at or below the horizon.
        Computed in float32, vectorised across pairs (within about 1e-5 relative of float64), or with
        ``double`` in float64 (several times slower, the reference). Runs in parallel without the GIL.
        """
    def merl_table(self, double: bool = False) -> _F64:
        """The BRDF at every MERL bin, as :meth:`eval` gives it: ``(3, 90, 90, 180)`` in 1/sr, with
        MERL's missing marker -1 where a bin's directions do not both lie strictly above the surface.
        """
    @property
    def path(self) -> Path:
        """The file the measurement was read from."""
    @property
    def description(self) -> str:
        """The file's ``description`` tensor ('' if it has none)."""
    @property
    def isotropic(self) -> bool:
        """Whether the material is isotropic (at most two incident azimuths measured)."""
    @property
    def reduction(self) -> int:
        """1, 2 or 4: an anisotropic measurement covers 2π / reduction of incident azimuths."""
    @property
    def jacobian(self) -> bool:
        """Whether the stored RGB values are multiplied by D(m) / (4 σ(ω_i))."""
    @property
    def theta_i(self) -> _F64:
        """Incident elevations (radians) at which the material was measured."""
    @property
    def phi_i(self) -> _F64:
        """Incident azimuths (radians) at which the material was measured."""
    @property
    def rgb(self) -> _F32:
        """The values of the ``rgb`` field as stored (float32, flattened; its shape is in :attr:`fields`)."""
    @property
    def fields(self) -> dict[str, tuple[str, tuple[int, ...]]]:
        """Every tensor of the file: ``{name: (numpy dtype name, shape)}``."""

# frenbrdf.models.reconstruct's weight stage
@final
class WeightFit:
    """Adam on one NBRDF's weights against a material's samples: forward, backward and update in one native loop."""

    def __new__(cls, tensors: list[_F32], decays: list[float], coords: _F32, values: _F32, cos_in: _F32,
                loss: str) -> WeightFit:
        """``tensors``: each layer's weights ``(out, in)`` and biases ``(out,)``, 6 inputs to 3 outputs; ``decays``:
        Adam's weight decay per tensor; ``coords`` ``(N, 6)``, mapped ``values`` ``(N, 3)``, ``cos_in`` ``(N,)``;
        ``loss``: ``'l1'`` or ``'mse'``."""
    def run(self, learning_rates: _F32, rows: _I64 | None = None) -> _F64:
        """One step per rate on the ``(steps, batch)`` rows (None: every sample); each step's loss before its
        update, stopping after the first that is not finite."""
    def gradient(self, weights: _F32, rows: _I64 | None = None) -> tuple[float, _F32]:
        """The loss on the ``(batch,)`` rows (None: every sample; with the tie's term, if any) and its gradient,
        flat, at the flat ``weights`` (each tensor in order), which become the fit's; Adam's state is untouched."""
    def tie(self, pairs: _F32, weight: float) -> None:
        """Ties the ``(P, 2, 6)`` pairs of NBRDF inputs: every step's loss adds ``weight`` times the mean over pairs
        and channels of |N(a) − N(b)| (its square for 'mse'). A weight of 0 unties them."""
    def tensors(self) -> list[_F32]:
        """Each tensor's values, flat, in the order given."""
