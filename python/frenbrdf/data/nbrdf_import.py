"""Published NBRDF weights → MERL tables.

Sztrajman, Rainer, Ritschel and Weyrich ("Neural BRDF Representation and Importance
Sampling", Computer Graphics Forum 2021) fitted one small MLP per MERL material and
published the weights as Keras ``.h5`` files (MIT licence). This module evaluates such a
network at every MERL bin and writes the result as a MERL ``.binary`` file, giving
MERL-format tables derived from the measured materials.

The network
    Dense layers stored as ``dense_<n>/dense_<n>/kernel:0`` (shape ``(in, out)``) and
    ``.../bias:0`` (shape ``(out,)``), applied in order of ``n``; ReLU after every layer
    but the last, then ``exp(x) − 1`` (the published ``.json`` has ``"linear"`` on the
    last Dense layer followed by a ``Lambda`` computing ``K.exp(x) - 1``). The published
    fits are 6→21→21→3; any number and width of hidden layers is accepted.

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
>>> from frenbrdf.data.nbrdf_import import import_nbrdf, load_keras_nbrdf, nbrdf_merl_table
>>> import_nbrdf(["merl-nbrdf/gold-paint.h5"], "merl-tables")        # doctest: +SKIP
[PosixPath('merl-tables/gold-paint.binary')]
>>> table = nbrdf_merl_table(load_keras_nbrdf("merl-nbrdf/gold-paint.h5"))  # doctest: +SKIP
>>> table.shape                                                       # doctest: +SKIP
(3, 90, 90, 180)
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from pathlib import Path

import h5py
import numpy as np
import torch
from tqdm import tqdm

from ..io.merl import FILE_BYTES, write_merl
from ..io.outputs import OutputFolder, check_free_space
from ..io.paths import input_file
from ..models.nbrdf import MAX_WIDTH, NBRDF, nbrdf_forward
from ..models.nbrdf import nbrdf_merl_table as _write_table

#: One Dense layer: kernel ``(in, out)`` and bias ``(out,)``, float64.
Layer = tuple[np.ndarray, np.ndarray]

#: Input size (H and D) and output size (RGB) of an NBRDF.
N_INPUTS, N_OUTPUTS = 6, 3

#: The most links a weight file may hold (a Keras NBRDF holds about a dozen): a larger file is not one.
MAX_ENTRIES = 10_000

_DENSE_GROUP = re.compile(r"dense_(\d+)")
# Rows evaluated at once: small blocks stay in cache (and bound the memory).
_CHUNK_ROWS = 2048


def load_keras_nbrdf(path: str | os.PathLike) -> list[Layer]:
    """Reads the Dense layers of a Keras NBRDF weight file.

    Parameters
    ----------
    path
        A Keras ``.h5`` weight file holding groups ``dense_<n>/dense_<n>`` with datasets
        ``kernel:0`` and ``bias:0``.

    Returns
    -------
    list of (kernel, bias)
        One pair per Dense layer, ordered by layer number (``dense_10`` after
        ``dense_9``): kernel float64 ``(in, out)``, bias float64 ``(out,)``.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        Not an HDF5 file or truncated; an external link, data kept in other files, or a soft
        link that does not resolve (:func:`_check_structure`); no Dense layers; a missing kernel or bias;
        weights in a layer that is not Dense; shapes that do not chain from 6 inputs to
        3 outputs; a NaN or infinite weight. The message names the file and the layer.
    """
    path = input_file(path, "NBRDF weight file")
    try:
        with h5py.File(path, "r") as file:
            _check_structure(file, path)
            layers = _read_dense_layers(file, path)
    except (FileNotFoundError, IsADirectoryError, PermissionError):
        raise
    except OSError as error:
        # h5py reports a wrong signature or a short file as a plain OSError.
        raise ValueError(f"{path}: not a readable HDF5 file (not HDF5, or truncated): {error}") from error
    except ValueError as error:
        if str(path) in str(error):
            raise
        raise ValueError(f"{path}: not a readable NBRDF weight file ({error})") from None
    except (KeyError, RuntimeError, TypeError) as error:
        # h5py's errors for what HDF5 allows but a weight file never holds (an unsupported dtype, say).
        raise ValueError(f"{path}: not a readable NBRDF weight file ({type(error).__name__}: {error})") from None
    _check_layers(layers, path)
    return [layer for _, layer in layers]


def _check_structure(file: h5py.File, path: Path) -> None:
    """Walks every link of the file before any layer is read; a ValueError names the first bad one.

    Refused: an external link, and a dataset whose data lie in other files (external storage, a
    virtual dataset), which would make reading this file read others; a soft link that does not
    resolve (dangling, or a loop of soft links), which is damage; more than :data:`MAX_ENTRIES`
    links (a Keras NBRDF holds a dozen). Soft links that resolve are allowed; groups reached twice
    through hard links are walked once.
    """
    seen, pending, count = set(), [file], 0
    while pending:
        group = pending.pop()
        for name in group:
            count += 1
            if count > MAX_ENTRIES:
                raise ValueError(f"{path}: more than {MAX_ENTRIES:,} entries; a Keras NBRDF weight file holds a few "
                                 "dense_<n> groups")
            where = f"{group.name.rstrip('/')}/{name}"
            link = group.get(name, getlink=True)
            if isinstance(link, h5py.ExternalLink):
                raise ValueError(f"{path}: {where} is an external link to {link.filename}:{link.path}; frenbrdf "
                                 "reads nothing outside the file it is given")
            try:
                item = group[name]
            except (KeyError, RuntimeError) as error:  # RuntimeError: "too many links", a loop
                kind = "a loop of soft links" if isinstance(error, RuntimeError) else "a link to nothing"
                target = f" to {link.path}" if isinstance(link, h5py.SoftLink) else ""
                raise ValueError(f"{path}: {where} is {kind}{target}, which does not resolve") from None
            if isinstance(link, h5py.SoftLink):
                continue  # its target is reached through hard links as well
            if isinstance(item, h5py.Dataset) and (item.is_virtual or item.external):
                raise ValueError(f"{path}: dataset {where} keeps its data in other files (external storage or a "
                                 "virtual dataset); frenbrdf reads nothing outside the file it is given")
            if isinstance(item, h5py.Group) and item.id not in seen:
                seen.add(item.id)
                pending.append(item)


def _read_dense_layers(file: h5py.File, path: Path) -> list[tuple[str, Layer]]:
    """The ``(name, (kernel, bias))`` of every ``dense_<n>`` group, sorted by ``n``."""
    names = sorted((name for name in file if _DENSE_GROUP.fullmatch(name)),
                   key=lambda name: int(_DENSE_GROUP.fullmatch(name).group(1)))
    if not names:
        raise ValueError(f"{path}: no Dense layer groups (dense_1, dense_2, ...) found; "
                         f"top-level entries are {sorted(file)}")
    for name in file:
        # A layer with weights that is not Dense (a batch norm, say) would change the
        # network: refuse rather than evaluate something else.
        if name not in names and isinstance(file[name], h5py.Group) and _holds_datasets(file[name]):
            raise ValueError(f"{path}: layer {name!r} has weights but is not a Dense layer (dense_<n>); "
                             "only Dense layers are supported")
    return [(name, (_dataset(file, f"{name}/{name}/kernel:0", path), _dataset(file, f"{name}/{name}/bias:0", path)))
            for name in names]


def _holds_datasets(group: h5py.Group) -> bool:
    # visititems stops at, and returns, the first value other than None.
    return group.visititems(lambda _, item: isinstance(item, h5py.Dataset) or None) is not None


def _dataset(file: h5py.File, key: str, path: Path) -> np.ndarray:
    item = file.get(key)
    if not isinstance(item, h5py.Dataset):
        raise ValueError(f"{path}: missing dataset {key!r}")
    if not (np.issubdtype(item.dtype, np.floating) or np.issubdtype(item.dtype, np.integer)):
        raise ValueError(f"{path}: dataset {key!r} has dtype {item.dtype}, expected real numbers")
    if item.size > MAX_WIDTH * MAX_WIDTH:  # checked before reading: a huge layer is refused, not evaluated for minutes
        raise ValueError(f"{path}: dataset {key!r} has shape {item.shape}; an NBRDF layer is at most "
                         f"{MAX_WIDTH} × {MAX_WIDTH}")
    return np.asarray(item[()], dtype=np.float64)


def _check_layers(layers: list[tuple[str, Layer]], path: Path) -> None:
    """Raises ValueError unless the layers chain from 6 inputs to 3 outputs, all finite."""
    n_in, source = N_INPUTS, "the network input (H, D)"
    for name, (kernel, bias) in layers:
        if kernel.ndim != 2 or bias.ndim != 1 or bias.shape[0] != kernel.shape[1]:
            raise ValueError(f"{path}: layer {name!r} has kernel shape {kernel.shape} and bias shape "
                             f"{bias.shape}; expected (in, out) and (out,)")
        if kernel.shape[0] != n_in:
            raise ValueError(f"{path}: layer {name!r} takes {kernel.shape[0]} inputs but {source} has {n_in}")
        if not 1 <= kernel.shape[1] <= MAX_WIDTH:
            raise ValueError(f"{path}: layer {name!r} is {kernel.shape[1]} wide; an NBRDF's layers are 1 … "
                             f"{MAX_WIDTH} wide")
        for weight, values in (("kernel", kernel), ("bias", bias)):
            bad = np.argwhere(~np.isfinite(values))
            if len(bad):
                raise ValueError(f"{path}: layer {name!r} {weight} holds NaN or infinite values "
                                 f"(first at index {tuple(int(i) for i in bad[0])})")
        n_in, source = kernel.shape[1], f"layer {name!r}"
    if n_in != N_OUTPUTS:
        raise ValueError(f"{path}: the last layer {layers[-1][0]!r} has {n_in} outputs, expected "
                         f"{N_OUTPUTS} (RGB)")


def evaluate_keras_nbrdf(layers: list[Layer], h, d) -> np.ndarray:
    """Evaluates an NBRDF at half vectors ``h`` and difference vectors ``d``.

    Parameters
    ----------
    layers
        ``(kernel, bias)`` pairs as returned by :func:`load_keras_nbrdf`.
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
    # One thread: torch's threads cost far more than they save on these thin products
    # (measured 3-10x slower on 2 busy cores; single-threaded it matches numpy).
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with torch.inference_mode():
            for start in range(0, len(x), _CHUNK_ROWS):
                rows = torch.from_numpy(np.array(x[start:start + _CHUNK_ROWS]))  # a writable copy, in cache
                out[start:start + _CHUNK_ROWS] = torch.expm1(nbrdf_forward(params, rows[None]))[0].numpy()
    finally:
        torch.set_num_threads(threads)
    return out


def keras_nbrdf(layers: list[Layer]) -> NBRDF:
    """The network as a :class:`frenbrdf.NBRDF` (float32 weights; output ``exp(x) − 1``).

    ``exp(x) − 1`` is the log-relative mapping with f_ref = 0 and ε = 1
    (:data:`frenbrdf.data.fitting.EXP_MINUS_ONE`), so the NBRDF evaluates, renders and
    writes MERL tables like any decoded or fitted one.
    """
    from .fitting import EXP_MINUS_ONE

    params = [torch.from_numpy(np.asarray(array, dtype=np.float32))[None] for kernel, bias in layers
              for array in (kernel.T, bias)]
    return NBRDF(params, EXP_MINUS_ONE)


def nbrdf_merl_table(layers: list[Layer]) -> np.ndarray:
    """Evaluates an NBRDF at every MERL bin.

    Parameters
    ----------
    layers
        ``(kernel, bias)`` pairs as returned by :func:`load_keras_nbrdf`.

    Returns
    -------
    numpy.ndarray
        float64 ``(3, 90, 90, 180)`` in physical units, ready for
        :func:`frenbrdf.io.merl.write_merl`: the network output clamped to ≥ 0 on bins above
        the horizon, ``−CHANNEL_SCALES[c]`` (stored value −1, MERL's missing marker)
        on the others (written by :func:`frenbrdf.models.nbrdf.nbrdf_merl_table`).
    """
    return _write_table(lambda inputs: _forward(layers, inputs))


def import_nbrdf(weight_paths: Iterable[str | os.PathLike], out_dir: str | os.PathLike, *,
                 overwrite: bool = False, progress: bool = True) -> list[Path]:
    """Converts NBRDF weight files to MERL files ``out_dir/<stem>.binary``.

    Every weight file is read and checked before anything is written, so one bad file
    stops the import with no output at all.

    Parameters
    ----------
    weight_paths
        Keras ``.h5`` weight files (see :func:`load_keras_nbrdf`).
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
    networks = [load_keras_nbrdf(path) for path in paths]

    with out.staged() as staging:
        bar = tqdm(zip(paths, names, networks), total=len(paths), desc="import-nbrdf", unit="material",
                   disable=not progress)
        for path, name, layers in bar:
            table = nbrdf_merl_table(layers)
            if not np.all(np.isfinite(table)):  # finite weights so large that exp(x) − 1 overflows
                raise ValueError(f"{path}: the network's output is not finite at {np.sum(~np.isfinite(table)):,} "
                                 "MERL bins (its weights are too large); not an NBRDF of a material")
            write_merl(staging / name, table)
    return [out.path / name for name in names]
