"""Published NBRDF weights → MERL tables.

Sztrajman, Rainer, Ritschel and Weyrich ("Neural BRDF Representation and Importance
Sampling", Computer Graphics Forum 2021) fitted one small MLP per MERL material and
published the weights as Keras ``.h5`` files (MIT licence). This module evaluates such a
network at every MERL bin and writes the result as a MERL ``.binary`` file, giving
MERL-format tables derived from the measured materials.

The network
    Read by :func:`frenbrdf.io.keras.read_keras_nbrdf` (Dense layers ``dense_<n>``, ReLU after
    every layer but the last, then ``exp(x) − 1``: the published ``.json`` has ``"linear"`` on the
    last Dense layer followed by a ``Lambda`` computing ``K.exp(x) - 1``).

The input convention
    The 6-vector is (H, D) in Cartesian coordinates with φ_h = 0:
    H = (sin θ_h, 0, cos θ_h), D = (sin θ_d cos φ_d, sin θ_d sin φ_d, cos θ_d), exactly
    what :func:`frenbrdf.numerics.coords.rusinkiewicz_to_half_diff` returns for
    (θ_h, 0, θ_d, φ_d). The output is RGB reflectance in MERL's physical units (stored
    value × channel scale).

The table
    Every bin of :func:`frenbrdf.io.merl.merl_bin_grid` is evaluated. Bins outside
    :func:`frenbrdf.io.merl.merl_above_horizon` are marked missing exactly as a measured
    MERL file marks them (stored value −1); on the others, the few slightly negative
    network outputs are clamped to 0.

Examples
--------
>>> from frenbrdf.data.nbrdf_import import import_nbrdf, keras_merl_table
>>> from frenbrdf.io.keras import read_keras_nbrdf
>>> import_nbrdf(["merl-nbrdf/gold-paint.h5"], "merl-tables")        # doctest: +SKIP
[PosixPath('merl-tables/gold-paint.binary')]
>>> table = keras_merl_table(read_keras_nbrdf("merl-nbrdf/gold-paint.h5"))  # doctest: +SKIP
>>> table.shape                                                       # doctest: +SKIP
(3, 90, 90, 180)
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from ..io.keras import N_INPUTS, N_OUTPUTS, Layer, keras_weights, read_keras_nbrdf
from ..io.merl import FILE_BYTES, TABLE_AXES, write_merl
from ..io.outputs import OutputFolder, check_free_space
from ..io.reflectance import check_reflectance
from ..models.nbrdf import NBRDF, nbrdf_forward, nbrdf_merl_table, one_torch_thread
from .fitting import EXP_MINUS_ONE

# Rows evaluated at once: small blocks stay in cache (and bound the memory).
_CHUNK_ROWS = 2048


def evaluate_keras_nbrdf(layers: list[Layer], h, d) -> np.ndarray:
    """Evaluates an NBRDF at half vectors ``h`` and difference vectors ``d``.

    Parameters
    ----------
    layers
        ``(kernel, bias)`` pairs as returned by :func:`frenbrdf.io.keras.read_keras_nbrdf`.
    h, d
        Cartesian H and D, ``(..., 3)``, broadcast against each other (see the module
        docstring for the convention).

    Returns
    -------
    numpy.ndarray
        float64 RGB reflectance ``(..., 3)``: ReLU after every hidden layer, then
        ``exp(x) − 1``. Not clamped: values down to −1 are possible.
    """
    if not layers:
        raise ValueError("layers must hold at least one (kernel, bias) pair")
    h, d = np.broadcast_arrays(np.asarray(h, dtype=np.float64), np.asarray(d, dtype=np.float64))
    if h.ndim == 0 or h.shape[-1] != 3:
        raise ValueError(f"h and d must have shape (..., 3), got {np.shape(h)} after broadcasting")
    x = np.concatenate([h, d], axis=-1).reshape(-1, N_INPUTS)
    return _forward(layers, x).reshape(*h.shape[:-1], N_OUTPUTS)


def _forward(layers: list[Layer], x: np.ndarray) -> np.ndarray:
    """The network on rows ``x`` ``(n, in)`` → ``(n, out)``, float64.

    The forward pass is :func:`frenbrdf.models.nbrdf.nbrdf_forward` (the one reference
    implementation) in float64, followed by ``exp(x) − 1`` without the cancellation near 0.
    """
    params = [torch.as_tensor(array, dtype=torch.float64)[None] for kernel, bias in layers
              for array in (kernel.T, bias)]
    x = np.asarray(x, dtype=np.float64)
    out = np.empty((len(x), N_OUTPUTS))
    # One thread: measured 3-10x faster than torch's threads on 2 busy cores; single-threaded it matches numpy.
    with one_torch_thread(), torch.inference_mode():
        for start in range(0, len(x), _CHUNK_ROWS):
            rows = torch.from_numpy(np.array(x[start:start + _CHUNK_ROWS]))  # a writable copy, in cache
            out[start:start + _CHUNK_ROWS] = torch.expm1(nbrdf_forward(params, rows[None]))[0].numpy()
    return out


def keras_nbrdf(layers: list[Layer]) -> NBRDF:
    """The network as a :class:`frenbrdf.NBRDF` (float32 weights, :func:`frenbrdf.io.keras.keras_weights`; output
    ``exp(x) − 1``).

    ``exp(x) − 1`` is the log-relative mapping with f_ref = 0 and ε = 1
    (:data:`frenbrdf.data.fitting.EXP_MINUS_ONE`, one mapping shared by every such NBRDF), so the NBRDF evaluates,
    renders and writes MERL tables like any decoded or fitted one.
    """
    return NBRDF([p[None] for p in keras_weights(layers).params], EXP_MINUS_ONE)


def keras_merl_table(layers: list[Layer]) -> np.ndarray:
    """The network evaluated in float64 at every MERL bin, as
    :func:`frenbrdf.models.nbrdf.nbrdf_merl_table` writes a network.

    Parameters
    ----------
    layers
        ``(kernel, bias)`` pairs as returned by :func:`frenbrdf.io.keras.read_keras_nbrdf`.

    Returns
    -------
    numpy.ndarray
        float64 ``(3, 90, 90, 180)`` in physical units, ready for
        :func:`frenbrdf.io.merl.write_merl`: the network output clamped to ≥ 0 on bins above
        the horizon, ``−CHANNEL_SCALES[c]`` (stored value −1, MERL's missing marker)
        on the others.
    """
    return nbrdf_merl_table(lambda inputs: _forward(layers, inputs))


def import_nbrdf(weight_paths: Iterable[str | os.PathLike], out_dir: str | os.PathLike, *,
                 overwrite: bool = False, progress: bool = True) -> list[Path]:
    """Converts NBRDF weight files to MERL files ``out_dir/<stem>.binary``.

    Every weight file is read and checked before anything is written, so one bad file
    stops the import with no output at all.

    Parameters
    ----------
    weight_paths
        Keras ``.h5`` weight files (see :func:`frenbrdf.io.keras.read_keras_nbrdf`).
    out_dir
        Destination folder (the output rule of :mod:`frenbrdf.io.outputs`): new, empty, or an earlier
        import's, which grows; the files are moved in once all are written, each atomically.
    overwrite
        Replace a file an earlier import wrote, and write beside the user's files (never replacing one).
    progress
        Show a progress bar on stderr.

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of ``weight_paths``.

    Raises
    ------
    ValueError
        No weight files, two files with the same stem (they would write the same
        output), or a bad weight file (the message names it).
    FileNotFoundError
        A weight file does not exist.
    """
    paths = [Path(p) for p in weight_paths]
    if not paths:
        raise ValueError("no NBRDF weight files given")
    by_stem: dict[str, list[Path]] = {}
    for path in paths:
        by_stem.setdefault(path.stem, []).append(path)
    clashes = {stem: group for stem, group in by_stem.items() if len(group) > 1}
    if clashes:
        listed = "; ".join(f"{stem}: {', '.join(map(str, group))}" for stem, group in clashes.items())
        raise ValueError(f"weight files with the same name would write the same output file ({listed})")

    out = OutputFolder.claim(out_dir, command="import-nbrdf", inputs=paths, overwrite=overwrite, additive=True,
                             option="out_dir")
    names = [f"{path.stem}.binary" for path in paths]
    out.check_names(names)
    check_free_space(out.target, len(names) * FILE_BYTES, f"{len(names)} MERL files")
    networks = [read_keras_nbrdf(path) for path in paths]

    with out.staged() as staging:
        bar = tqdm(zip(paths, names, networks, strict=True), total=len(paths), desc="import-nbrdf", unit="material",
                   disable=not progress)
        for path, name, layers in bar:
            table = keras_merl_table(layers)
            # What the MERL reader would refuse is not written: finite weights so large that exp(x) − 1 overflows
            # or passes any reflectance.
            check_reflectance(table, path, what="network outputs at the MERL bins (not a material's NBRDF)",
                              axes=TABLE_AXES)
            write_merl(staging / name, table)
    return [out.path / name for name in names]
