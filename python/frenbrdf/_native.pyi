"""Type stubs for the private native module. Use the public API in `frenbrdf`."""

import os
from pathlib import Path

import numpy as np
import numpy.typing as npt

__version__: str
CHANNEL_SCALES: tuple[float, float, float]
FILE_BYTES: int
BSDF_HORIZON: float

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]
F32 = npt.NDArray[np.float32]

def num_threads() -> int: ...

# MERL I/O and lookup
def read_merl(path: str, physical_units: bool = True) -> F64: ...
def write_merl(path: str, table: F64, physical_units: bool = True) -> None: ...
def merl_lookup(table: F64, angles: F64, method: str) -> F64: ...
def merl_lookup_directions(table: F64, wi: F64, wo: F64, method: str) -> F64: ...
def merl_bin_to_angles(bins: F64) -> F64: ...
def merl_angles_to_bin(angles: F64) -> I64: ...

# Coordinates
def directions_to_rusinkiewicz(wi: F64, wo: F64) -> F64: ...
def rusinkiewicz_to_directions(angles: F64) -> tuple[F64, F64]: ...
def half_diff_vectors(wi: F64, wo: F64) -> tuple[F64, F64]: ...
def rusinkiewicz_to_half_diff(angles: F64) -> tuple[F64, F64]: ...

# kNN interpolation
class KnnInterpolator:
    def __init__(self, src: F64, dst: F64, k: int, sigma: float) -> None: ...
    def apply(self, values: F64) -> F64: ...
    @property
    def k(self) -> int: ...
    @property
    def n_src(self) -> int: ...
    @property
    def n_dst(self) -> int: ...
    @property
    def indices(self) -> I64: ...
    @property
    def weights(self) -> F64: ...

# Spherical harmonic transform (arrays are 2-D: (batch, nlat·nlon) or (batch, (lmax+1)²))
class ShtPlan:
    def __init__(self, nlat: int, nlon: int, lmax: int, grid: str, dtype: str) -> None: ...
    def analysis(self, maps: npt.NDArray[np.floating]) -> npt.NDArray[np.floating]: ...
    def synthesis(self, coeffs: npt.NDArray[np.floating]) -> npt.NDArray[np.floating]: ...
    def analysis_adjoint(self, coeffs: npt.NDArray[np.floating]) -> npt.NDArray[np.floating]: ...
    def degrees_orders(self) -> I64: ...
    def rings(self) -> tuple[F64, F64]: ...

# RGL measured BRDFs (`tensor_file` .bsdf, Dupuy & Jakob 2018)
class BsdfMeasurement:
    """A measured RGB BRDF of the RGL material database (an ``*_rgb.bsdf`` file), ready to evaluate."""

    @staticmethod
    def read(path: str | os.PathLike[str]) -> BsdfMeasurement:
        """Reads and checks a ``.bsdf`` file.

        Raises ``FileNotFoundError`` (and other ``OSError``) for the file system, and
        ``frenbrdf.exceptions.BsdfFormatError`` for a malformed file or a spectral one
        (only RGB files, with an ``rgb`` tensor, are supported).
        """
    def eval(self, wi: F64, wo: F64) -> F64:
        """The BRDF at ``(n, 3)`` direction pairs (float64, C-contiguous, local frame with z the
        normal; normalised here): ``(n, 3)`` RGB reflectance in 1/sr, not multiplied by cos θ_o,
        negative measurements clamped to 0, and 0 where either direction is at or below the horizon.
        Runs in parallel without the GIL.
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
    def theta_i(self) -> F64:
        """Incident elevations (radians) at which the material was measured."""
    @property
    def phi_i(self) -> F64:
        """Incident azimuths (radians) at which the material was measured."""
    @property
    def rgb(self) -> F32:
        """The values of the ``rgb`` field as stored (float32, flattened; its shape is in :attr:`fields`)."""
    @property
    def fields(self) -> dict[str, tuple[str, tuple[int, ...]]]:
        """Every tensor of the file: ``{name: (numpy dtype name, shape)}``."""

# frenbrdf.models.reconstruct's weight stage
class WeightFit:
    """Adam on one NBRDF's weights against a material's samples: forward, backward and update in one native loop."""

    def __init__(self, tensors: list[F32], decays: list[float], coords: F32, values: F32, cos_in: F32,
                 loss: str) -> None:
        """``tensors``: each layer's weights ``(out, in)`` and biases ``(out,)``, 6 inputs to 3 outputs; ``decays``:
        Adam's weight decay per tensor; ``coords`` ``(N, 6)``, mapped ``values`` ``(N, 3)``, ``cos_in`` ``(N,)``;
        ``loss``: ``'l1'`` or ``'mse'``."""
    def run(self, learning_rates: F32, rows: I64 | None = None) -> F64:
        """One step per rate on the ``(steps, batch)`` rows (None: every sample); each step's loss before its
        update, stopping after the first that is not finite."""
    def tensors(self) -> list[F32]:
        """Each tensor's values, flat, in the order given."""
