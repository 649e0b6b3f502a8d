"""Checkpoints: the format version, atomic save, checked load, and the run's mapping.

A checkpoint (``best.pt``, ``last.pt``) is a dict written by ``torch.save``: ``format``,
``method``, ``config`` (the training config as JSON), ``split``, ``model`` (state dict),
``optimizer``, ``generator``, ``epoch``, ``best`` and ``history``.

Format 2 keeps the mapping's f_ref table (17.5 MB per-bin) out of the checkpoints: it is
written once per run folder, as ``mapping.npz`` beside them. Format 1 held it in every
checkpoint; such run folders still load.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch

from .atomic import atomic_path
from .merl import SHAPE
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
    """A checkpoint, checked to be one of the readable formats and to hold what every checkpoint holds:
    ``method`` and ``config`` (strings) and ``model`` (a dict of tensors). :meth:`frenbrdf.Model.from_checkpoint`
    checks the config and the weights' shapes; :func:`load_for_resume` checks the rest of ``last.pt``.

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
    version = checkpoint["format"]
    if isinstance(version, bool) or version not in READABLE_FORMATS:
        raise ValueError(f"{path}: checkpoint format {version!r:.40}; this frenbrdf reads formats {READABLE_FORMATS}")
    missing = [key for key in ("method", "config", "model") if key not in checkpoint]
    if missing:
        raise ValueError(f"{path}: not a complete frenbrdf model: it lacks {', '.join(missing)}")
    for key in ("method", "config"):
        if not isinstance(checkpoint[key], str):
            raise ValueError(f"{path}: {key} must be a string, got {type(checkpoint[key]).__name__}")
    weights = checkpoint["model"]
    if not isinstance(weights, dict) or not all(isinstance(name, str) and isinstance(value, torch.Tensor)
                                                for name, value in weights.items()):
        raise ValueError(f"{path}: model (the weights) must be a dict of named tensors")
    return checkpoint


def load_for_resume(path: str | os.PathLike, network: torch.nn.Module, optimizer: torch.optim.Optimizer,
                    config: dict | None = None, model_as_read: Callable[[dict], dict] | None = None) -> dict:
    """The checkpoint a training run resumes from (``last.pt``), every field it restores checked.

    Parameters
    ----------
    path
        The checkpoint.
    network, optimizer
        The run's network and optimiser, as the resumed run builds them (on the ``meta`` device is enough:
        only their shapes and parameter groups are read, nothing is loaded into them).
    config
        The resumed run's training config (:func:`frenbrdf.configs.to_dict`): its method, model and seed must be
        the checkpoint's, checked first, so a mismatch is named as such rather than as weights that do not fit.
    model_as_read
        The saved model config (a dict) as a model reads it today (fields added since it was saved at their
        defaults), for that comparison; None: compared as saved.

    Returns
    -------
    dict
        The checkpoint: its weights and optimiser state fit ``network`` and ``optimizer``, its ``generator`` is a
        torch CPU generator's state, ``epoch`` an integer ≥ 0, ``best``/``bests`` the best epochs and scores,
        ``history`` a list of epochs, ``config`` a training config (JSON); ``split`` is left to the caller, which
        knows splits.

    Raises
    ------
    ValueError
        A field is missing or wrong; the message names the file and the field.
    """
    checkpoint = load(path)
    missing = [key for key in RESUME_KEYS if key not in checkpoint]
    if missing:
        raise ValueError(f"{path}: not a checkpoint to resume from: it lacks {', '.join(missing)}")
    try:
        _check_resume_fields(checkpoint, network, optimizer, config, model_as_read)
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None
    return checkpoint


def _difference(saved, given, where: str) -> tuple[str, object, object]:
    """The first place (a dotted key) where two configs differ, with the two values there."""
    if isinstance(saved, dict) and isinstance(given, dict):
        for key in sorted(set(saved) | set(given)):
            if saved.get(key) != given.get(key):
                return _difference(saved.get(key), given.get(key), f"{where}.{key}")
    return where, saved, given


#: What a checkpoint a run resumes from holds beyond :func:`load`'s fields.
RESUME_KEYS = ("split", "optimizer", "generator", "epoch", "best", "history")


def _check_resume_fields(checkpoint: dict, network: torch.nn.Module, optimizer: torch.optim.Optimizer,
                         expected: dict | None = None, model_as_read: Callable[[dict], dict] | None = None) -> None:
    """Raises ValueError (naming the field) for the first field of ``checkpoint`` a resume cannot restore."""
    from ..presets import SELECTION_RULES
    from .jsonfile import parse_json

    config = parse_json(checkpoint["config"], "config", "training config")
    if not isinstance(config.get("model"), dict) or not _is_integer(config.get("seed")):
        raise ValueError("config: holds no model settings or seed")
    if model_as_read is not None:
        config = {**config, "model": model_as_read(config["model"])}
    for key in ("method", "seed", "model"):
        if expected is not None and key in expected and config.get(key) != expected[key]:
            where = _difference(config.get(key), expected[key], key)
            raise ValueError(f"the run was trained with another {where[0]} ({where[1]!r:.60}, this resume asks for "
                             f"{where[2]!r:.60}); resume with the run's own config (--config RUN/config.json)")
    _check_weights(checkpoint["model"], network.state_dict())
    _check_optimizer(checkpoint["optimizer"], optimizer, {name: p for name, p in network.named_parameters()})
    try:
        torch.Generator().set_state(checkpoint["generator"])
    except (TypeError, RuntimeError, ValueError):
        raise ValueError(f"generator: not the state of a torch CPU random generator "
                         f"({_describe(checkpoint['generator'])})") from None
    epoch = checkpoint["epoch"]
    if not _is_integer(epoch) or epoch < 0:
        raise ValueError(f"epoch must be an integer ≥ 0, got {epoch!r:.40}")
    bests = checkpoint.get("bests", {"best": checkpoint["best"]})
    if not isinstance(bests, dict) or not set(bests) <= {*SELECTION_RULES, "best"}:
        raise ValueError(f"bests must map selection rules {SELECTION_RULES} to best epochs, got {bests!r:.80}")
    for rule, best in {"best": checkpoint["best"], **bests}.items():
        if not (isinstance(best, dict) and set(best) == {"epoch", "val"} and _is_integer(best["epoch"])
                and _is_number(best["val"]) and -1 <= best["epoch"] <= epoch):
            field = "best" if rule == "best" else f"bests[{rule!r}]"
            raise ValueError(f"{field} must be {{'epoch': an epoch ≤ {epoch}, 'val': a number}}, got {best!r:.80}")
    history = checkpoint["history"]
    if not isinstance(history, list):
        raise ValueError(f"history must be a list of epochs, got {_describe(history)}")
    for i, entry in enumerate(history):
        if not (isinstance(entry, dict) and _is_integer(entry.get("epoch")) and -1 <= entry["epoch"] <= epoch
                and all(isinstance(key, str) and _is_number(value) for key, value in entry.items())):
            raise ValueError(f"history[{i}] must be an epoch's record (an integer epoch ≤ {epoch} and named "
                             f"numbers), got {entry!r:.80}")


def _check_weights(weights: dict, expected: dict) -> None:
    """That ``weights`` (a dict of tensors) has the names and shapes of ``expected`` (a state dict) and is finite."""
    given = {name: tuple(value.shape) for name, value in weights.items()}
    wanted = {name: tuple(value.shape) for name, value in expected.items()}
    if given != wanted:
        name = (sorted(set(given) ^ set(wanted)) or [n for n in wanted if given[n] != wanted[n]])[0]
        raise ValueError(f"model (the weights) does not fit the run's model config: {name} is "
                         f"{given.get(name, 'missing')}, the config gives {wanted.get(name, 'no such tensor')} "
                         "(resume a run with its own config.json)")
    bad = [name for name, value in weights.items() if not (value.is_floating_point() and torch.isfinite(value).all())]
    if bad:
        raise ValueError(f"model (the weights): {', '.join(bad[:3])} not finite floating-point numbers")


def _check_optimizer(state, optimizer: torch.optim.Optimizer, parameters: dict) -> None:
    """That ``state`` is a state dict of ``optimizer``: its parameter groups (same sizes, hyperparameters of the
    same kinds) and, per parameter, tensors of the parameter's shape."""
    fresh = optimizer.state_dict()["param_groups"]
    if not (isinstance(state, dict) and isinstance(state.get("state"), dict)
            and isinstance(state.get("param_groups"), list)):
        raise ValueError(f"optimizer must be an optimiser state ({{'state': …, 'param_groups': […]}}), got "
                         f"{_describe(state)}")
    groups = state["param_groups"]
    if len(groups) != len(fresh) or not all(isinstance(g, dict) and isinstance(g.get("params"), list) for g in groups):
        raise ValueError(f"optimizer: {len(groups)} parameter groups, the run's optimiser has {len(fresh)}")
    shapes = [tuple(p.shape) for group in optimizer.param_groups for p in group["params"]]
    for i, (group, ours) in enumerate(zip(groups, fresh, strict=True)):
        if len(group["params"]) != len(ours["params"]) or not all(_is_integer(p) for p in group["params"]):
            raise ValueError(f"optimizer: parameter group {i} holds {len(group['params'])} parameters, the run's "
                             f"optimiser {len(ours['params'])} (was the run trained with another config?)")
        for key, default in ours.items():
            if key != "params" and key in group and not _same_kind(group[key], default):
                raise ValueError(f"optimizer: parameter group {i}: {key} must be {_kind_of(default)}, got "
                                 f"{group[key]!r:.40}")
        if not group.get("lr", 0) >= 0:
            raise ValueError(f"optimizer: parameter group {i}: lr must be ≥ 0, got {group['lr']}")
    indices = [p for group in groups for p in group["params"]]
    if sorted(indices) != list(range(len(shapes))):
        raise ValueError(f"optimizer: its parameter indices are not 0 … {len(shapes) - 1}")
    shape_of = dict(zip(indices, shapes, strict=True))
    for index, values in state["state"].items():
        if index not in shape_of or not isinstance(values, dict):
            raise ValueError(f"optimizer: state of {index!r:.20}, which is no parameter of the run's optimiser")
        for key, value in values.items():
            if key == "step":
                if not (isinstance(value, torch.Tensor) and value.numel() == 1 or _is_number(value)):
                    raise ValueError(f"optimizer: the step count of parameter {index} is {_describe(value)}")
            elif not (isinstance(value, torch.Tensor) and tuple(value.shape) == shape_of[index]
                      and value.is_floating_point() and torch.isfinite(value).all()):
                raise ValueError(f"optimizer: {key} of parameter {index} must be finite numbers of shape "
                                 f"{shape_of[index]}, got {_describe(value)}")



def _same_kind(value, default) -> bool:
    """Whether an optimiser hyperparameter read from a file is of the kind the optimiser's own default is."""
    if isinstance(default, bool) or default is None:
        return value is None or isinstance(value, bool)
    if isinstance(default, (int, float)):
        return _is_number(value) and math.isfinite(value)
    if isinstance(default, (tuple, list)):
        return (isinstance(value, (tuple, list)) and len(value) == len(default)
                and all(_is_number(v) and math.isfinite(v) for v in value))
    return type(value) is type(default)


def _kind_of(default) -> str:
    """What :func:`_same_kind` accepts for ``default``, in words."""
    if isinstance(default, bool) or default is None:
        return "true, false or None"
    if isinstance(default, (int, float)):
        return "a finite number"
    if isinstance(default, (tuple, list)):
        return f"{len(default)} finite numbers"
    return f"a {type(default).__name__}"


def _is_integer(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _describe(value) -> str:
    """What a field holds, briefly, for messages."""
    if isinstance(value, torch.Tensor):
        return f"a {value.dtype} tensor of shape {tuple(value.shape)}"
    if isinstance(value, np.ndarray):
        return f"a {value.dtype} array of shape {value.shape}"
    return f"{value!r:.60}"


def save_mapping(folder: str | os.PathLike, state: dict) -> None:
    """Writes a mapping's state (``reference``, ``epsilon``) as the run folder's ``mapping.npz``."""
    with atomic_path(Path(folder) / MAPPING_FILE) as temporary:
        np.savez(temporary, reference=np.asarray(state["reference"], dtype=np.float32),
                 epsilon=np.float64(state["epsilon"]), offset=np.float64(state.get("offset", 0.0)))


def load_mapping(path: str | os.PathLike, checkpoint: dict) -> dict:
    """The mapping state of the checkpoint read from ``path``: in it (format 1) or beside it (format 2), checked
    (:func:`check_mapping_state`)."""
    if checkpoint["format"] == 1:
        return check_mapping_state(checkpoint.get("mapping"), f"{path}: mapping")
    file = Path(path).parent / MAPPING_FILE
    if not file.exists():
        raise FileNotFoundError(f"{path}: its run folder holds no {MAPPING_FILE} (the mapping of format-2 "
                                "checkpoints is stored once per run folder; copy it along with the checkpoint)")
    saved = checked_npz(file, "mapping file", member_bytes=64 << 20)  # a per-bin f_ref is 17.5 MB
    return check_mapping_state(saved, str(file))


def check_mapping_state(state, where: str) -> dict:
    """A mapping's state (``reference``, ``epsilon``, ``offset``: :meth:`LogRelativeMapping.state
    <frenbrdf.models.mapping.LogRelativeMapping.state>`) read from a file, every field checked; ``where`` names
    the file in messages. ``offset`` may be absent (states saved before it existed: 0).

    Raises
    ------
    ValueError
        A field is missing, of the wrong type or shape, or out of range.
    """
    if not isinstance(state, dict):
        raise ValueError(f"{where}: not a frenbrdf mapping (a table of reference, epsilon, offset), got "
                         f"{_describe(state)}")
    missing = [key for key in ("reference", "epsilon") if key not in state]
    if missing:
        raise ValueError(f"{where}: not a frenbrdf mapping: it lacks {', '.join(missing)}")
    reference = state["reference"]
    reference = reference.numpy() if isinstance(reference, torch.Tensor) else np.asarray(reference)
    if reference.dtype.kind not in "fiu" or reference.shape not in ((3,), SHAPE):
        raise ValueError(f"{where}: reference (f_ref) must be numbers of shape (3,) or {SHAPE}, got "
                         f"{_describe(reference)}")
    if not np.all(np.isfinite(reference)) or reference.min() < 0:
        raise ValueError(f"{where}: reference (f_ref) must be finite and ≥ 0")
    epsilon = _scalar(state["epsilon"], "epsilon", where)
    if not 0 < epsilon < math.inf:
        raise ValueError(f"{where}: epsilon: the mapping's ε must be a positive number, got {epsilon}")
    offset = _scalar(state.get("offset", 0.0), "offset", where)
    if offset not in (0.0, 1.0):
        raise ValueError(f"{where}: offset (the mapping's c) must be 0 or 1, got {offset}")
    return {"reference": reference, "epsilon": epsilon, "offset": offset}


def _scalar(value, field: str, where: str) -> float:
    """One real number stored as a Python number, a 0-d array or a one-element tensor."""
    if isinstance(value, torch.Tensor):
        value = value.numpy()
    array = np.asarray(value)
    if array.shape != () or array.dtype.kind not in "fiu":
        raise ValueError(f"{where}: {field} must be one number, got {_describe(value)}")
    return float(array)
