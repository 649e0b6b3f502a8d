"""Checkpoints: the format version, atomic save, checked load, and the run's mapping.

A checkpoint (``best.pt``, ``last.pt``) is a dict written by ``torch.save``: ``format``,
``method``, ``config`` (the training config as JSON), ``split``, ``model`` (state dict),
``optimizer``, ``generator``, ``epoch``, ``best`` and ``history``.

Format 2 keeps the mapping's f_ref table (17.5 MB per-bin) out of the checkpoints: it is
written once per run folder, as ``mapping.npz`` beside them. Format 1 held it in every
checkpoint; such run folders still load.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch

from .atomic import atomic_path
from .paths import checked_npz, torch_load

FORMAT = 2
"""The format :func:`save` writes."""
READABLE_FORMATS = (1, 2)
"""Formats :func:`load` accepts."""
MAPPING_FILE = "mapping.npz"
"""The run folder's mapping (format 2)."""


def save(path: str | os.PathLike, state: dict) -> None:
    """``torch.save`` of ``state`` (with ``format`` set), atomically: never a half-written file."""
    with atomic_path(path) as temporary:
        torch.save({**state, "format": FORMAT}, temporary)


def load(path: str | os.PathLike) -> dict:
    """A checkpoint, checked to be one of the readable formats.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        The file is damaged, not a frenbrdf checkpoint, or of a format this version cannot read.
    """
    checkpoint = torch_load(path, "frenbrdf checkpoint")
    if not isinstance(checkpoint, dict) or "format" not in checkpoint:
        raise ValueError(f"{path}: not a frenbrdf checkpoint")
    if checkpoint["format"] not in READABLE_FORMATS:
        raise ValueError(f"{path}: checkpoint format {checkpoint['format']!r}; this frenbrdf reads formats "
                         f"{READABLE_FORMATS}")
    return checkpoint


def save_mapping(folder: str | os.PathLike, state: dict) -> None:
    """Writes a mapping's state (``reference``, ``epsilon``) as the run folder's ``mapping.npz``."""
    with atomic_path(Path(folder) / MAPPING_FILE) as temporary:
        np.savez(temporary, reference=np.asarray(state["reference"], dtype=np.float32),
                 epsilon=np.float64(state["epsilon"]), offset=np.float64(state.get("offset", 0.0)))


def load_mapping(path: str | os.PathLike, checkpoint: dict) -> dict:
    """The mapping state of the checkpoint read from ``path``: in it (format 1) or beside it (format 2)."""
    if checkpoint["format"] == 1:
        mapping = checkpoint["mapping"]
        return {"reference": np.asarray(mapping["reference"]), "epsilon": float(mapping["epsilon"])}
    file = Path(path).parent / MAPPING_FILE
    if not file.exists():
        raise FileNotFoundError(f"{path}: its run folder holds no {MAPPING_FILE} (the mapping of format-2 "
                                "checkpoints is stored once per run folder; copy it along with the checkpoint)")
    saved = checked_npz(file, "mapping file", member_bytes=64 << 20)  # a per-bin f_ref is 17.5 MB
    try:
        return {"reference": saved["reference"], "epsilon": float(saved["epsilon"]),
                "offset": float(saved["offset"]) if "offset" in saved else 0.0}
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"{file}: not a frenbrdf mapping (missing or wrong {error})") from None
