"""An NBRDF as its files hold it: the ``.pt`` that ``fit-nbrdf`` and ``reconstruct`` write.

A saved NBRDF is a dict written by ``torch.save``: ``params`` (the layers' weights ``(out, in)`` and biases
``(out,)``, in order), ``reference`` (the mapping's f_ref, float32), ``epsilon``, ``offset`` and ``ordered``.
:func:`read_nbrdf` returns it as :class:`NBRDFWeights`, checked as a file; the network itself is a model's
(:meth:`frenbrdf.NBRDF.from_weights` builds it and checks the layers: shapes, widths, finite values). The file format
lives here and the construction with the models because a file is read below the models, which turn it into a
network.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import torch

from .atomic import atomic_path
from .paths import torch_load

#: The NBRDF's input (H and D as Cartesian 3-vectors) and its output (RGB).
N_INPUTS, N_OUTPUTS = 6, 3
#: The widest hidden layer and the most hidden layers an NBRDF may have (Sztrajman's has 21, HyperBRDF's 60): a
#: width read from a file is checked against it before anything is evaluated (a width of 20000 takes minutes).
MAX_WIDTH, MAX_LAYERS = 1024, 16


@dataclass
class NBRDFWeights:
    """One NBRDF as a file holds it (:meth:`frenbrdf.NBRDF.from_weights` makes the network)."""

    params: list[torch.Tensor]
    """The weights ``(out, in)`` and biases ``(out,)`` of each layer, in order, without a material axis."""
    reference: np.ndarray
    """The mapping's f_ref: ``(3,)`` or a table ``(3, 90, 90, 180)``."""
    epsilon: float
    """The mapping's ε."""
    offset: float = 0.0
    """The mapping's offset."""
    ordered: bool = False
    """Whether the network tells the two orders of a pair apart."""
    source: str = ""
    """The file read ('' for weights made in memory): what a message about them names."""
    what: str = "NBRDF"
    """What the file is, for messages: ``"saved NBRDF"``, ``"Keras NBRDF"``."""


def read_nbrdf(path: str | os.PathLike) -> NBRDFWeights:
    """Reads an NBRDF written by :func:`write_nbrdf`.

    Raises
    ------
    FileNotFoundError, IsADirectoryError
        No such file, or a folder.
    ValueError
        Not a torch file, or one that holds objects other than tensors and plain data, or not a saved NBRDF (no
        list of parameters, no reference tensor, an ``ordered`` flag that is not a bool); the message names the
        file.
    """
    state = torch_load(path, "saved NBRDF")
    try:
        if not isinstance(state, dict) or not isinstance(state.get("params"), (list, tuple)):
            raise ValueError("it holds no list of parameters")
        reference = state["reference"]
        if not isinstance(reference, torch.Tensor):
            raise ValueError(f"its reference is a {type(reference).__name__}, not a tensor")
        ordered = state.get("ordered", False)  # files written before ordered NBRDFs hold reciprocal ones
        if not isinstance(ordered, bool):
            raise ValueError(f"its 'ordered' flag is a {type(ordered).__name__}, not a bool")
        return NBRDFWeights(list(state["params"]), reference.numpy(), state["epsilon"], state.get("offset", 0.0),
                            ordered, os.fspath(path), "saved NBRDF")
    except KeyError as error:
        raise ValueError(f"{path}: not a saved NBRDF (it lacks {error})") from None
    except ValueError as error:
        raise ValueError(f"{path}: not a valid saved NBRDF: {error}") from None


def write_nbrdf(path: str | os.PathLike, weights: NBRDFWeights) -> None:
    """Writes one NBRDF (:meth:`frenbrdf.NBRDF.weights`) atomically, f_ref as float32 as run folders store it (a
    per-bin f_ref is then 17.5 MB, not 35)."""
    if not isinstance(weights, NBRDFWeights):
        raise TypeError(f"{os.fspath(path)}: a saved NBRDF holds NBRDFWeights (NBRDF.weights()), got "
                        f"{type(weights).__name__}")
    with atomic_path(path) as temporary:
        torch.save({"params": list(weights.params),
                    "reference": torch.from_numpy(np.asarray(weights.reference, dtype=np.float32)),
                    "epsilon": weights.epsilon, "offset": weights.offset, "ordered": weights.ordered}, temporary)
