"""A training run folder, opened: its config, split, history, mapping and best model.

:func:`~frenbrdf.training.train` returns one; evaluation, sweeps, the demo and the CLI
open run folders only through it.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

from ..configs import from_dict
from ..data.folders import Split
from ..io.jsonfile import read_json
from ..models.autoencoder import Model
from ..presets import AUGMENTATION
from .config import TrainConfig, selection_score


class Run:
    """A run folder written by :func:`~frenbrdf.training.train`.

    Parameters
    ----------
    path
        The run folder (holding ``config.json``).
    seconds
        Training time, when the run was just trained (``train`` sets it).

    Raises
    ------
    FileNotFoundError
        The folder does not exist or is not a run folder.
    """

    def __init__(self, path: str | os.PathLike, *, seconds: float | None = None):
        self.path = Path(path)
        if not (self.path / "config.json").exists():
            raise FileNotFoundError(f"{self.path} is not a training run folder (it holds no config.json)")
        self.seconds = seconds

    def __repr__(self) -> str:
        return f"Run({str(self.path)!r})"

    @functools.cached_property
    def config(self) -> TrainConfig:
        saved = self._json("config.json")
        # Runs from before augmentation existed trained on the tables only.
        saved.setdefault("augment", AUGMENTATION["paper"] | {"preset": "paper"})
        return from_dict(TrainConfig, saved, str(self.path / "config.json"))

    @functools.cached_property
    def split(self) -> Split:
        return Split.from_json(self._json("split.json"), str(self.path / "split.json"))

    @property
    def method(self) -> str:
        return self.config.method

    @property
    def data(self) -> Path:
        """The folder of MERL files the run was trained on."""
        return Path(self.config.data)

    @property
    def history(self) -> list[dict]:
        """One entry per epoch (epoch −1: the untrained model); read afresh, it grows while training runs."""
        if not (self.path / "history.json").exists():
            return []
        history = self._json("history.json", expect=list)
        if not all(isinstance(entry, dict) and isinstance(entry.get("epoch"), int) and all(
                isinstance(value, (int, float)) and not isinstance(value, bool) for value in entry.values())
                for entry in history):
            raise ValueError(f"{self.path / 'history.json'}: not a training history (a list of epochs' records)")
        return history

    @property
    def best(self) -> dict:
        """The history entry of the best epoch by the run's selection rule (``TrainConfig.select``: the lowest
        validation reconstruction loss, or the highest validation render PSNR), the first of ties."""
        return self.best_by(self.config.select)

    def best_by(self, rule: str) -> dict:
        """The history entry of the best epoch by ``rule`` (:data:`frenbrdf.presets.SELECTION_RULES`)."""
        judged = [(score, entry) for entry in self.history if (score := selection_score(entry, rule)) is not None]
        if not judged:
            raise ValueError(f"{self.path}: no trained epoch has been measured by the rule {rule!r} yet")
        return min(judged, key=lambda pair: pair[0])[1]  # the first of ties

    @property
    def best_epoch(self) -> int:
        return self.best["epoch"]

    @property
    def best_val(self) -> float:
        """Validation reconstruction loss (L1, cosine-weighted, mapped space) of the best epoch."""
        return self.best["val_rec"]

    def model(self) -> Model:
        """The best checkpoint as a :class:`~frenbrdf.Model`."""
        if not (self.path / "best.pt").exists():
            raise FileNotFoundError(f"{self.path} holds no best.pt: training has not finished an epoch")
        return Model.load(self.path)

    def _json(self, name: str, expect: type = dict):
        try:
            return read_json(self.path / name, f"run folder's {name}", expect=expect)
        except FileNotFoundError:
            raise FileNotFoundError(f"{self.path} lacks {name}: not a complete training run folder") from None
