"""Per-material NBRDF fitting (Sztrajman et al. 2021): the quality ceiling of the autoencoders.

One small MLP per material, trained directly on the material's valid MERL bins with
Adam (lr 5e-4), batches of 512 and the L1 loss on ln(1 + f cos θ_i). The network's
output is exp(x) − 1, which is our log-relative mapping with f_ref = 0 and ε = 1, so a
fitted material is an ordinary :class:`frenbrdf.NBRDF` (and so are the published fits
of ``import-nbrdf``'s Keras files).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import torch
from tqdm.auto import tqdm

from ..io.atomic import atomic_path
from ..io.merl import N_BINS, SHAPE
from ..models.mapping import LogRelativeMapping
from ..models.nbrdf import NBRDF, NBRDFConfig, bin_geometry, mapped_samples, nbrdf_forward

#: Sztrajman's output activation exp(x) − 1 as a mapping.
EXP_MINUS_ONE = LogRelativeMapping(np.zeros(3), epsilon=1.0)


@dataclass
class FitConfig:
    """Settings of a per-material fit (defaults: Sztrajman et al.)."""

    hidden: tuple[int, ...] = (21, 21)
    """Hidden widths of the NBRDF."""
    epochs: int = 10
    """Passes over the material's valid bins."""
    batch: int = 512
    """Bins per step."""
    lr: float = 5e-4
    """Adam learning rate."""
    seed: int = 0

    def __post_init__(self):
        self.hidden = tuple(int(h) for h in self.hidden)
        if self.epochs < 1 or self.batch < 1 or not self.lr > 0 or min(self.hidden, default=0) < 1:
            raise ValueError(f"invalid fit config {self}: epochs, batch, lr and hidden widths must be positive")


def fit_nbrdf(table, config: FitConfig = FitConfig(), progress: bool = True) -> NBRDF:
    """Fits one NBRDF to a MERL table ``(3, 90, 90, 180)`` (reflectance, missing < 0)."""
    table = np.asarray(table, dtype=np.float64)
    if table.shape != SHAPE:
        raise ValueError(f"table must have shape {SHAPE}, got {table.shape}")
    if not np.all(np.isfinite(table)):
        raise ValueError("table holds NaN or inf values")
    flat = table.reshape(3, N_BINS)
    bins = np.flatnonzero(np.all(flat >= 0, axis=0))
    if len(bins) == 0:
        raise ValueError("table holds no valid bin")
    geometry = bin_geometry()
    return _fit(geometry.half_diff[bins], geometry.cos_in[bins], flat[:, bins].T, config, progress)


def fit_nbrdf_samples(values, directions, config: FitConfig = FitConfig(), progress: bool = True) -> NBRDF:
    """Fits one NBRDF to scattered samples: reflectance ``(N, 3)`` at the pairs ``(wi, wo)``, as
    :func:`frenbrdf.models.reconstruct.reconstruct` takes them (e.g. a measurement in both orders of each pair,
    :func:`frenbrdf.render.scoring.truth_samples`, which a table cannot hold). ``epochs`` are passes over them."""
    _, coords, cos_in = mapped_samples(EXP_MINUS_ONE, values, directions)  # checks them; the fit maps its own way
    return _fit(torch.from_numpy(coords.astype(np.float32)), torch.from_numpy(cos_in.astype(np.float32)),
                np.asarray(values, dtype=np.float64), config, progress)


def _fit(coords: torch.Tensor, cos_in: torch.Tensor, values: np.ndarray, config: FitConfig, progress: bool) -> NBRDF:
    """Adam on L1 of ln(1 + f cos θ_i) over samples: NBRDF inputs ``(N, 6)``, cos θ_i ``(N,)``, reflectance ``(N, 3)``."""
    cos_in = cos_in.unsqueeze(-1)
    target = torch.log1p(torch.from_numpy(values.astype(np.float32)) * cos_in)
    torch.manual_seed(config.seed)
    params = [torch.nn.Parameter(p) for p in _initial_params(NBRDFConfig(config.hidden))]
    optimizer = torch.optim.Adam(params, lr=config.lr)
    generator = torch.Generator().manual_seed(config.seed)
    steps = (len(coords) + config.batch - 1) // config.batch
    for _ in tqdm(range(config.epochs), desc="fit NBRDF", disable=not progress, leave=False):
        order = torch.randperm(len(coords), generator=generator)
        for step in range(steps):
            rows = order[step * config.batch:(step + 1) * config.batch]
            predicted = torch.expm1(nbrdf_forward([p[None] for p in params], coords[rows][None]))[0].clamp_min(0)
            loss = (torch.log1p(predicted * cos_in[rows]) - target[rows]).abs().mean()
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            optimizer.step()
    return NBRDF([p.detach()[None] for p in params], EXP_MINUS_ONE)


def _initial_params(config: NBRDFConfig) -> list[torch.Tensor]:
    """Sztrajman's initialisation: weights uniform in ±0.05, biases 0."""
    return [torch.empty(shape).uniform_(-0.05, 0.05) if len(shape) == 2 else torch.zeros(shape)
            for shape in config.shapes()]


def save_nbrdf(path: str | os.PathLike, nbrdf: NBRDF) -> None:
    """Saves one NBRDF (weights, mapping, and whether it is ordered) atomically."""
    with atomic_path(path) as temporary:
        torch.save({"params": [p[0] for p in nbrdf.params], # f_ref as float32, as run folders store it: a per-bin f_ref is then 17.5 MB, not 35
                    "reference": torch.from_numpy(nbrdf.mapping.reference.astype(np.float32)),
                    "epsilon": nbrdf.mapping.epsilon, "offset": nbrdf.mapping.offset, "ordered": nbrdf.ordered},
                   temporary)


def load_nbrdf(path: str | os.PathLike) -> NBRDF:
    """Loads an NBRDF written by :func:`save_nbrdf`, checked whole (:func:`frenbrdf.models.nbrdf.check_params`:
    layer shapes and widths, finite weights; the mapping's f_ref and ε) before anything is evaluated."""
    from ..io.paths import torch_load

    state = torch_load(path, "saved NBRDF")
    try:
        if not isinstance(state, dict) or not isinstance(state.get("params"), (list, tuple)):
            raise ValueError("it holds no list of parameters")
        params = [p[None] if isinstance(p, torch.Tensor) else p for p in state["params"]]
        reference = state["reference"]
        if not isinstance(reference, torch.Tensor):
            raise ValueError(f"its reference is a {type(reference).__name__}, not a tensor")
        ordered = state.get("ordered", False)  # files written before ordered NBRDFs hold reciprocal ones
        if not isinstance(ordered, bool):
            raise ValueError(f"its 'ordered' flag is a {type(ordered).__name__}, not a bool")
        return NBRDF(params, LogRelativeMapping(reference.numpy(), state["epsilon"], state.get("offset", 0.0)), ordered)
    except KeyError as error:
        raise ValueError(f"{path}: not a saved NBRDF (it lacks {error})") from None
    except ValueError as error:
        raise ValueError(f"{path}: not a valid saved NBRDF: {error}") from None
