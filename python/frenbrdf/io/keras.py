"""Published Keras NBRDFs: the ``.h5`` weight files of Sztrajman et al.

Sztrajman, Rainer, Ritschel and Weyrich ("Neural BRDF Representation and Importance Sampling", Computer Graphics
Forum 2021) fitted one small MLP per MERL material and published the weights as Keras ``.h5`` files (MIT licence).
Dense layers are stored as ``dense_<n>/dense_<n>/kernel:0`` (shape ``(in, out)``) and ``.../bias:0`` (shape
``(out,)``), applied in order of ``n``; ReLU after every layer but the last, then ``exp(x) − 1``. The published fits
are 6→21→21→3; any number of hidden layers up to :data:`~frenbrdf.io.nbrdf.MAX_LAYERS`, each up to
:data:`~frenbrdf.io.nbrdf.MAX_WIDTH` wide, is accepted.

:func:`read_keras_nbrdf` reads and checks the layers (float64, as the file holds them); :func:`keras_weights` gives
them as an NBRDF's weights (:class:`~frenbrdf.io.nbrdf.NBRDFWeights`, float32, mapping ``exp(x) − 1``: f_ref 0,
ε 1). Evaluating them is :mod:`frenbrdf.data.nbrdf_import`'s.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import h5py
import numpy as np
import torch

from .nbrdf import MAX_LAYERS, MAX_WIDTH, N_INPUTS, N_OUTPUTS, NBRDFWeights
from .paths import input_file

#: One Dense layer: kernel ``(in, out)`` and bias ``(out,)``, float64.
Layer = tuple[np.ndarray, np.ndarray]

#: The most links a weight file may hold (a Keras NBRDF holds about a dozen): a larger file is not one.
MAX_ENTRIES = 10_000

_DENSE_GROUP = re.compile(r"dense_(\d+)")


def read_keras_nbrdf(path: str | os.PathLike) -> list[Layer]:
    """Reads the Dense layers of a Keras NBRDF weight file.

    Parameters
    ----------
    path
        A Keras ``.h5`` weight file holding groups ``dense_<n>/dense_<n>`` with datasets
        ``kernel:0`` and ``bias:0``.

    Returns
    -------
    list of Layer
        One ``(kernel, bias)`` pair per Dense layer, ordered by layer number (``dense_10`` after
        ``dense_9``): kernel float64 ``(in, out)``, bias float64 ``(out,)``.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        Not an HDF5 file or truncated; an external link, data kept in other files, or a soft
        link that does not resolve (``_check_structure``); no Dense layers; a missing kernel or bias;
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
    numbered = [(int(match.group(1)), name) for name in file if (match := _DENSE_GROUP.fullmatch(name))]
    names = [name for _, name in sorted(numbered, key=lambda pair: pair[0])]
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
    """Raises ValueError unless the layers chain from 6 inputs to 3 outputs, all finite, through at most
    :data:`~frenbrdf.io.nbrdf.MAX_LAYERS` hidden layers."""
    if len(layers) - 1 > MAX_LAYERS:
        raise ValueError(f"{path}: {len(layers) - 1} hidden layers; an NBRDF has at most {MAX_LAYERS}")
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


def keras_weights(layers: list[Layer], source: str | os.PathLike = "") -> NBRDFWeights:
    """The layers as an NBRDF's weights: each kernel transposed to ``(out, in)``, float32; the mapping ``exp(x) − 1``
    (f_ref 0, ε 1), which is the network's own output."""
    params = [torch.from_numpy(np.asarray(array, dtype=np.float32)) for kernel, bias in layers
              for array in (kernel.T, bias)]
    return NBRDFWeights(params, np.zeros(3), 1.0, source=os.fspath(source), what="Keras NBRDF")
