"""The model shipped inside the package, and how a run folder is packed into one.

This folder holds, beside this module, the packed model that :meth:`frenbrdf.Model.pretrained`
and ``frenbrdf reconstruct --model pretrained`` load (``release/train_shipped_model.py`` trains and
packs it; ``docs/pretrained.md`` is its model card):

``model.pt``
    The network's weights in float16 (halves the size; float32 again when loaded), the
    method and the training config (JSON), with :data:`FORMAT`.
``mapping.npz``
    f_ref compactly: ln(f_ref + ε) quantised to 16 bits over its range, stored as differences
    along φ_d and compressed. 1.3 MB instead of 17.5 MB for a per-bin f_ref of 10 MERL-derived
    materials, with a relative error of (f_ref + ε) — and so of every decoded reflectance
    + ε — below 1e-4 (``docs/pretrained.md`` has the table of the options measured).
    A per-channel f_ref is 3 numbers and stored as they are.
``card.json``
    The model card: :data:`VERSION`, the training command, data, seed, held-out quality.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import torch

from ...io import checkpoints
from ...io.atomic import atomic_path, save_json
from ...io.jsonfile import read_json
from ...io.merl import SHAPE
from ...io.paths import checked_npz, torch_load

#: Where the shipped model lives: this package folder.
PACKAGE_DIR = Path(__file__).resolve().parent
#: The packed files.
MODEL_FILE, MAPPING_FILE, CARD_FILE = "model.pt", "mapping.npz", "card.json"
#: The format of the packed files that :func:`pack_pretrained` writes and :func:`load_packed` reads.
FORMAT = 1
#: The version of the shipped model (the card's ``version``; docs/pretrained.md states it).
VERSION = "12"
#: Quantisation levels of ln(f_ref + ε): 16 bits.
LEVELS = 65535


def pack_mapping(state: dict) -> dict[str, np.ndarray]:
    """A mapping's state (:meth:`LogRelativeMapping.state`) as compact arrays (see the module docstring)."""
    reference = np.asarray(state["reference"], dtype=np.float64)
    packed = {"epsilon": np.float64(state["epsilon"]), "offset": np.float64(state.get("offset", 0.0))}
    if reference.ndim == 1:  # per channel: three numbers
        return {**packed, "reference": reference}
    log = np.log(reference + state["epsilon"])
    low, high = float(log.min()), float(log.max())
    levels = np.round((log - low) / max(high - low, 1e-30) * LEVELS).astype(np.int32)
    # Differences along φ_d are small where f_ref is smooth, which is what makes it compress.
    steps = np.diff(levels, axis=-1, prepend=0).astype(np.int32)
    return {**packed, "log_steps": steps.astype(np.int16) if np.abs(steps).max() < 2**15 else steps,
            "log_range": np.array([low, high])}


def unpack_mapping(packed, where: str = "packed mapping") -> dict:
    """The inverse of :func:`pack_mapping`: a mapping state with f_ref as float64, every field checked
    (``where`` names the file in messages).

    Raises
    ------
    ValueError
        A field is missing, of the wrong type or shape, or out of range.
    """
    if "reference" in packed:
        return checkpoints.check_mapping_state(packed, where)
    missing = [key for key in ("epsilon", "log_steps", "log_range") if key not in packed]
    if missing:
        raise ValueError(f"{where}: not a packed mapping: it lacks {', '.join(missing)}")
    steps, bounds = np.asarray(packed["log_steps"]), np.asarray(packed["log_range"])
    if steps.dtype.kind not in "iu" or steps.shape != SHAPE:
        raise ValueError(f"{where}: log_steps must be integers of shape {SHAPE}, got {steps.dtype} {steps.shape}")
    if bounds.dtype.kind not in "fiu" or bounds.shape != (2,) or not (np.all(np.isfinite(bounds))
                                                                    and bounds[0] <= bounds[1]):
        raise ValueError(f"{where}: log_range must be two finite numbers low ≤ high, got {bounds!r:.80}")
    low, high = (float(v) for v in bounds)
    levels = np.cumsum(steps, axis=-1, dtype=np.int64)
    if levels.min() < 0 or levels.max() > LEVELS:
        raise ValueError(f"{where}: log_steps add up to levels outside 0 … {LEVELS}: damaged")
    state = checkpoints.check_mapping_state({"reference": np.zeros(3), **{k: packed[k] for k in ("epsilon", "offset")
                                                                          if k in packed}}, where)
    state["reference"] = np.maximum(np.exp(levels / LEVELS * (high - low) + low) - state["epsilon"], 0.0)
    return state


def pack_pretrained(run_dir: str | os.PathLike, dest: str | os.PathLike | None = None, *, card: dict | None = None,
                    half: bool = True) -> dict[str, int]:
    """Packs a run folder's best checkpoint into ``dest`` (default: the package's own folder).

    Parameters
    ----------
    run_dir
        A training run folder (``best.pt``, ``mapping.npz``).
    dest
        Folder of the three packed files (made if missing).
    card
        What the model card says beyond what the checkpoint knows (training command, data,
        held-out quality); ``format``, ``version``, ``method`` and ``model`` are added.
    half
        Store the weights as float16 (else float32).

    Returns
    -------
    dict
        Bytes of each file written.
    """
    checkpoint = checkpoints.load(Path(run_dir) / "best.pt")
    mapping = checkpoints.load_mapping(Path(run_dir) / "best.pt", checkpoint)
    return pack_checkpoint(checkpoint, mapping, dest, card=card, half=half)


def check_pack_destination(dest: str | os.PathLike | None, inputs=()) -> Path:
    """Where a model may be packed, checked before any work: not one of ``inputs`` (the runs or packed models it
    is made from), their folder, nor one holding them; and a folder holding none of the three file names, or a
    packed model (:func:`load_packed` reads it) that the new one replaces. A training run's ``mapping.npz`` or a
    user's ``card.json`` is never replaced."""
    from ...io.outputs import check_not_input

    dest = Path(dest) if dest is not None else PACKAGE_DIR
    check_not_input(dest.resolve(), inputs, option="dest", out=dest)
    if dest.exists() and not dest.is_dir():
        raise ValueError(f"dest {dest} exists and is not a folder")
    present = [name for name in (MODEL_FILE, MAPPING_FILE, CARD_FILE) if (dest / name).exists()]
    if present:
        try:
            load_packed(dest)
        except (OSError, ValueError) as error:
            raise ValueError(f"dest {dest} holds {', '.join(present)}, not a packed model's files ({error}); pack "
                             "into an empty folder or an earlier packed model's") from None
    return dest


def pack_checkpoint(checkpoint: dict, mapping: dict, dest: str | os.PathLike | None = None, *,
                    card: dict | None = None, half: bool = True) -> dict[str, int]:
    """Packs a checkpoint (``method``, ``config``, ``model``) and its mapping's state: :func:`pack_pretrained`
    without a run folder (e.g. a model assembled from others, ``release/pack_encoder_mean.py``). ``dest`` is
    checked by :func:`check_pack_destination` first."""
    dest = check_pack_destination(dest)
    dtype = torch.float16 if half else torch.float32
    packed = {"format": FORMAT, "method": checkpoint["method"], "config": checkpoint["config"],
              "model": {name: value.to(dtype) for name, value in checkpoint["model"].items()}}
    arrays: dict[str, Any] = pack_mapping(mapping)  # Any: numpy's stubs take any ** key for allow_pickle (a bool)
    config = json.loads(checkpoint["config"])
    card = {"version": VERSION, **(card or {}), "format": FORMAT, "method": checkpoint["method"],
            "model": config["model"], "weights": "float16" if half else "float32"}
    dest.mkdir(parents=True, exist_ok=True)
    # All three written before any replaces its old file (the blocks' renames run as they end, one after the
    # other): a failure midway leaves the old model whole, never new weights beside an old mapping.
    with (atomic_path(dest / MODEL_FILE) as model_file, atomic_path(dest / MAPPING_FILE) as mapping_file,
          atomic_path(dest / CARD_FILE) as card_file):
        torch.save(packed, model_file)
        np.savez_compressed(mapping_file, **arrays)
        save_json(card_file, card)
    return {name: (dest / name).stat().st_size for name in (MODEL_FILE, MAPPING_FILE, CARD_FILE)}


def load_packed(folder: str | os.PathLike | None = None) -> tuple[dict, dict, dict]:
    """The packed model of ``folder`` (default: the package's): a checkpoint-like dict (``model``, ``config``,
    ``method``), the mapping state and the card.

    Raises
    ------
    FileNotFoundError
        A packed file is absent (the package ships no model).
    ValueError
        A packed file is damaged or of another format; the message names it.
    """
    folder = Path(folder) if folder is not None else PACKAGE_DIR
    # exists(), not is_file(): a FIFO or a folder in their place is then named as such by the readers below
    missing = [name for name in (MODEL_FILE, MAPPING_FILE, CARD_FILE) if not (folder / name).exists()]
    if missing:
        raise FileNotFoundError(f"no pretrained model: {folder} lacks {', '.join(missing)}. This installation of "
                                "frenbrdf ships without one; train one and pass its run folder with --model RUN_DIR, "
                                "or pack one with release/train_shipped_model.py (docs/pretrained.md)")
    path = folder / MODEL_FILE
    packed = torch_load(path, "packed model")
    if not isinstance(packed, dict) or not {"format", "model", "config", "method"} <= set(packed):
        raise ValueError(f"{path}: not a packed frenbrdf model")
    if isinstance(packed["format"], bool) or packed["format"] != FORMAT:
        raise ValueError(f"{path}: packed-model format {packed['format']!r:.40}; this frenbrdf reads format {FORMAT}")
    # The method, config and weights are checked by Model.from_checkpoint, the mapping here.
    mapping = unpack_mapping(checked_npz(folder / MAPPING_FILE, "packed mapping", member_bytes=64 << 20),
                             str(folder / MAPPING_FILE))
    card = read_json(folder / CARD_FILE, "model card", max_bytes=1 << 20)
    return packed, mapping, card
