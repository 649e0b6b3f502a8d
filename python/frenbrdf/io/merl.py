"""Reading, writing and looking up MERL BRDF tables.

A MERL table is a float64 array of shape ``(3, 90, 90, 180)``: RGB × θ_h bins × θ_d bins
× φ_d bins. Bin ``(i, j, k)`` sits at θ_h = (i/90)² · π/2, θ_d = j/90 · π/2,
φ_d = k/180 · π. Negative entries mark missing measurements (below the horizon) and
must never be used as reflectance: :func:`valid_mask` tells which bins hold data.

Examples
--------
>>> import frenbrdf
>>> table = frenbrdf.read_merl("gold-paint.binary")              # doctest: +SKIP
>>> rgb = frenbrdf.merl_lookup(table, theta_h=0.1, theta_d=0.5, phi_d=1.0)  # doctest: +SKIP
"""

from __future__ import annotations

import errno
import os
import re

import numpy as np

from .. import _native
from ..exceptions import MerlFormatError
from ..numerics._arrays import rows
from .reflectance import check_reflectance

#: Table shape: (channel, θ_h, θ_d, φ_d).
SHAPE = (3, 90, 90, 180)
#: Number of bins per channel of a MERL table.
N_BINS = SHAPE[1] * SHAPE[2] * SHAPE[3]
#: Stored value × scale = reflectance, per channel (MERL's reference reader).
CHANNEL_SCALES = tuple(_native.CHANNEL_SCALES)
#: Size in bytes of every MERL file.
FILE_BYTES = _native.FILE_BYTES
#: The axes of a table, as messages name a bin.
TABLE_AXES = "(channel, θ_h, θ_d, φ_d)"


def read_merl(path: str | os.PathLike, *, physical_units: bool = True) -> np.ndarray:
    """Reads a MERL ``.binary`` file.

    Parameters
    ----------
    path
        The file.
    physical_units
        Apply MERL's channel scales (the default). ``False`` returns the values exactly
        as stored.

    Returns
    -------
    numpy.ndarray
        float64, shape ``(3, 90, 90, 180)``. Missing measurements stay negative,
        exactly as stored (times the channel scale).

    Raises
    ------
    MerlFormatError
        Wrong header dimensions, a size that does not match the header (e.g. a truncated
        file), a NaN/inf value or a reflectance above :data:`~frenbrdf.io.reflectance.MAX_REFLECTANCE`
        (:func:`~frenbrdf.io.reflectance.check_reflectance`); the message names the file and the problem.
    FileNotFoundError, IsADirectoryError, PermissionError
        As the operating system reports them.
    """
    from .paths import input_file

    path = input_file(path, "MERL file")
    table = _native.read_merl(os.fspath(path), physical_units)
    reflectance = table if physical_units else table * np.reshape(CHANNEL_SCALES, (3, 1, 1, 1))
    check_reflectance(reflectance, path, axes=TABLE_AXES, error=MerlFormatError)
    return table


def write_merl(path: str | os.PathLike, table, *, physical_units: bool = True) -> None:
    """Writes a table as a MERL file, atomically.

    The data go to a temporary file in the same folder, which is renamed over ``path``
    only once complete: a failure never leaves a half-written file behind.

    Writing is the exact inverse of :func:`read_merl`: ``read_merl(p)`` after
    ``write_merl(p, t)`` returns ``t`` for any table that came from ``read_merl``, and
    a file written here is reproduced byte for byte by reading and writing it again.
    (Reflectance is stored divided by a channel scale that is not a power of two, which
    maps a few pairs of neighbouring doubles to one; for files from other writers use
    ``physical_units=False`` on both sides for a byte-exact copy.)

    Parameters
    ----------
    path
        Destination file; replaced if it exists.
    table
        Real array of shape ``(3, 90, 90, 180)`` with finite values.
    physical_units
        ``table`` holds reflectance (the default) rather than stored values.

    Raises
    ------
    MerlFormatError
        Wrong shape or dtype, or a NaN/inf value (the message says where).
    """
    table = np.asarray(table)
    if not np.issubdtype(table.dtype, np.floating):
        raise MerlFormatError(f"{os.fspath(path)}: cannot write an array of dtype {table.dtype}; "
                              "a MERL table holds real floating-point values")
    if table.shape != SHAPE:
        raise MerlFormatError(f"{os.fspath(path)}: cannot write an array of shape {table.shape}; "
                              f"a MERL table is {SHAPE}")
    try:
        _native.write_merl(os.fspath(path), np.ascontiguousarray(table, dtype=np.float64), physical_units)
    except OSError as error:  # the native writer's message names its temporary file: name the one asked for
        reason = re.sub(r" at path \"[^\"]*\"", "", error.strerror or str(error))
        raise type(error)(error.errno or errno.EIO, reason, os.fspath(path)) from None
    # The native writer's temporary file is private (0600); the file gets the permissions of every other
    # output, those a newly created file gets under the umask.
    os.chmod(path, 0o666 & ~_umask())


def _umask() -> int:
    """The process's umask, read without changing it where Linux tells it (os.umask sets it to read it)."""
    try:
        for line in open("/proc/self/status"):
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except OSError:
        pass
    umask = os.umask(0o022)
    os.umask(umask)
    return umask


def valid_mask(table) -> np.ndarray:
    """Bins that hold a measurement in every channel: bool ``(90, 90, 180)``."""
    table = np.asarray(table)
    if table.shape != SHAPE:
        raise ValueError(f"table must have shape {SHAPE}, got {table.shape}")
    return np.all(table >= 0, axis=0)


def merl_bin_angles() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The angles of the bins along each axis: θ_h ``(90,)``, θ_d ``(90,)``, φ_d ``(180,)``."""
    theta_h = merl_bin_to_angles(np.stack([np.arange(90), np.zeros(90), np.zeros(90)], axis=-1))[:, 0]
    theta_d = merl_bin_to_angles(np.stack([np.zeros(90), np.arange(90), np.zeros(90)], axis=-1))[:, 1]
    phi_d = merl_bin_to_angles(np.stack([np.zeros(180), np.zeros(180), np.arange(180)], axis=-1))[:, 2]
    return theta_h, theta_d, phi_d


def merl_bin_grid() -> np.ndarray:
    """The (θ_h, θ_d, φ_d) angles of every bin: float64 ``(90, 90, 180, 3)``."""
    theta_h, theta_d, phi_d = merl_bin_angles()
    return np.stack(np.meshgrid(theta_h, theta_d, phi_d, indexing="ij"), axis=-1)


def merl_bin_rusinkiewicz() -> np.ndarray:
    """Rusinkiewicz angles (θ_h, φ_h = 0, θ_d, φ_d) of every bin: float64 ``(90, 90, 180, 4)``."""
    grid = merl_bin_grid()
    return np.stack([grid[..., 0], np.zeros(grid.shape[:-1]), grid[..., 1], grid[..., 2]], axis=-1)


def merl_bin_directions() -> tuple[np.ndarray, np.ndarray]:
    """Unit directions (ω_i, ω_o) of every bin (φ_h = 0), each ``(90, 90, 180, 3)``."""
    from ..numerics.coords import rusinkiewicz_to_directions

    return rusinkiewicz_to_directions(merl_bin_rusinkiewicz())


def merl_above_horizon() -> np.ndarray:
    """Bins whose directions (with φ_h = 0) both lie strictly above the surface.

    A measured MERL file has data exactly here; elsewhere it stores negative
    "missing" markers. Returns bool ``(90, 90, 180)``.
    """
    wi, wo = merl_bin_directions()
    return (wi[..., 2] > 0) & (wo[..., 2] > 0)


def merl_bin_to_angles(bins) -> np.ndarray:
    """Bin coordinates ``(..., 3)`` (integer or fractional) → angles (θ_h, θ_d, φ_d)."""
    flat, leading = rows("bins", bins, 3)
    return _native.merl_bin_to_angles(flat).reshape(*leading, 3)


def merl_angles_to_bin(angles) -> np.ndarray:
    """Angles (θ_h, θ_d, φ_d) ``(..., 3)`` → the MERL bin holding them, int64 ``(..., 3)``.

    As in MERL's reference reader: floor of the continuous index, θ's clamped to
    [0, π/2], φ_d folded into [0, π) by reciprocity.
    """
    flat, leading = rows("angles", angles, 3)
    return _native.merl_angles_to_bin(flat).reshape(*leading, 3)


def _check_method(method: str) -> str:
    if method not in ("nearest", "trilinear"):
        raise ValueError(f"method must be 'nearest' or 'trilinear', got {method!r}")
    return method


def _table(table) -> np.ndarray:
    table = np.asarray(table)
    if table.shape != SHAPE:
        raise ValueError(f"table must have shape {SHAPE}, got {table.shape}")
    return np.ascontiguousarray(table, dtype=np.float64)


def merl_lookup(table, theta_h, theta_d, phi_d, *, method: str = "trilinear") -> np.ndarray:
    """Evaluates a table at arbitrary Rusinkiewicz angles.

    Parameters
    ----------
    table
        ``(3, 90, 90, 180)``.
    theta_h, theta_d, phi_d
        Angles in radians, broadcast against each other.
    method
        ``"nearest"``: the nearest bin. ``"trilinear"``: linear in bin coordinates along
        each axis (θ_h on MERL's quadratic axis, periodic in φ_d), over the corners that
        hold a measurement.

    Returns
    -------
    numpy.ndarray
        RGB, shape ``broadcast_shape + (3,)``; negative where no measurement is available.
    """
    angles = np.stack(np.broadcast_arrays(theta_h, theta_d, phi_d), axis=-1)
    flat, leading = rows("angles", angles, 3)
    return _native.merl_lookup(_table(table), flat, _check_method(method)).reshape(*leading, 3)


def merl_lookup_directions(table, wi, wo, *, method: str = "trilinear") -> np.ndarray:
    """Evaluates a table at direction pairs ``wi``, ``wo`` of shape ``(..., 3)``.

    Returns RGB ``(..., 3)``; negative where either direction is below the horizon or no
    measurement is available.

    A direction exactly on the horizon (z = 0, θ = 90°) counts as above it; any z < 0 is
    below. For a table measured wherever :func:`merl_above_horizon` holds (as MERL's files
    are), ``"trilinear"`` finds measured corners for every pair above the horizon, grazing
    ones included, so it never returns the missing marker there; ``"nearest"`` may land
    in an unmeasured bin near grazing and return it.
    """
    wi_rows, leading = rows("wi", wi, 3)
    wo_rows, _ = rows("wo", wo, 3)
    if wi_rows.shape != wo_rows.shape:
        raise ValueError(f"wi and wo must have the same shape, got {np.shape(wi)} and {np.shape(wo)}")
    return _native.merl_lookup_directions(_table(table), wi_rows, wo_rows, _check_method(method)).reshape(*leading, 3)
