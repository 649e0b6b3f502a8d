"""The training config, and the presets of :mod:`frenbrdf.presets` laid over it."""

from __future__ import annotations

import dataclasses
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..configs import from_dict, merge, to_dict
from ..losses import LossConfig
from ..models.autoencoder import ModelConfig
from ..presets import METHODS, check_method, training_overrides


@dataclass
class TrainConfig:
    """One training run. Saved as ``config.json`` in the run folder and in every checkpoint."""

    method: str = "frenbrdf"
    """``frenbrdf``, ``nbrdf`` or ``hyperbrdf``: which preset :func:`config_for` starts from."""
    data: str = ""
    """Folder of MERL files."""
    out: str = ""
    """Run folder (created)."""
    seed: int = 0
    """Seeds the split, the initialisation and the sampling."""
    split: tuple[float, float, float] = (0.7, 0.1, 0.2)
    """Train/validation/test fractions, by material."""
    epochs: int = 200
    """Passes over the training materials."""
    batch_materials: int = 8
    """Materials per optimisation step (sharded across ranks under DDP)."""
    context_samples: int = 4000
    """Samples per material given to the encoder."""
    query_samples: int = 4000
    """Samples per material at which the reconstruction is compared."""
    lr: float = 1e-3
    """Adam learning rate."""
    grad_clip: float = 0.0
    """Clip the gradient norm to this (0: no clipping)."""
    device: str = "cpu"
    """``"cpu"``, ``"cuda"`` or ``"auto"``."""
    cache_dir: str = ""
    """Cache of true SH coefficients (default: ``$FRENBRDF_CACHE`` or ``~/.cache/frenbrdf``)."""
    progress: bool = True
    """Show progress bars."""
    model: ModelConfig = field(default_factory=ModelConfig)
    loss: LossConfig = field(default_factory=LossConfig)

    def __post_init__(self):
        problems = []
        if self.method not in METHODS:
            problems.append(f"method must be one of {tuple(METHODS)}, got {self.method!r}")
        for name in ("epochs", "batch_materials", "context_samples", "query_samples"):
            if int(getattr(self, name)) < 1:
                problems.append(f"{name} must be ≥ 1, got {getattr(self, name)}")
        if not (self.lr > 0 and math.isfinite(self.lr)):
            problems.append(f"lr must be a positive number, got {self.lr}")
        if not (self.grad_clip >= 0 and math.isfinite(self.grad_clip)):
            problems.append(f"grad_clip must be ≥ 0, got {self.grad_clip}")
        if self.device not in ("cpu", "cuda", "auto"):
            problems.append(f"device must be 'cpu', 'cuda' or 'auto', got {self.device!r}")
        if problems:
            raise ValueError("invalid training config: " + "; ".join(problems))
        self.split = tuple(self.split)

    @property
    def cache_folder(self) -> Path:
        """Where the true SH coefficients are cached."""
        return Path(self.cache_dir or os.environ.get("FRENBRDF_CACHE") or Path.home() / ".cache" / "frenbrdf")


def config_for(method: str, *, training: str | None = None, **overrides) -> TrainConfig:
    """The preset of a method (:data:`frenbrdf.presets.METHODS`), optionally with a training length
    (``"demo"``, ``"sweep"``), with top-level fields overridden."""
    check_method(method)
    layers = [METHODS[method]]
    if training is not None:
        layers.append(training_overrides(training))
    layers.append({key: to_dict(value) if dataclasses.is_dataclass(value) else value
                   for key, value in overrides.items()})
    settings = to_dict(TrainConfig(method=method))
    for layer in layers:
        settings = merge(settings, layer)
    return from_dict(TrainConfig, settings, f"the {method} preset")


def load_config(path: str | os.PathLike, **overrides) -> TrainConfig:
    """A JSON config file (any subset of :class:`TrainConfig`'s keys) over its method's preset."""
    try:
        data = json.loads(Path(path).read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: a config must be a JSON object, got {type(data).__name__}")
    data.update({key: value for key, value in overrides.items() if value is not None})
    base = to_dict(config_for(data.get("method", "frenbrdf")))
    return from_dict(TrainConfig, merge(base, data), str(path))
