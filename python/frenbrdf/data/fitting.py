"""Per-material NBRDF fitting (Sztrajman et al. 2021): the quality ceiling of the autoencoders.

One small MLP per material, trained directly on the material's valid MERL bins with
Adam (lr 5e-4), batches of 512 and the L1 loss on ln(1 + f cos θ_i). The network's
output is exp(x) − 1, which is our log-relative mapping with f_ref = 0 and ε = 1, so a
fitted material is an ordinary :class:`frenbrdf.NBRDF` (and so are the published fits
of ``import-nbrdf``'s Keras files).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from tqdm.auto import tqdm

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


def fit_nbrdf(table, config: FitConfig | None = None, progress: bool = True) -> NBRDF:
    """Fits one NBRDF to a MERL table ``(3, 90, 90, 180)`` (reflectance, missing < 0); ``config`` defaults to
    :class:`FitConfig`'s defaults."""
    config = FitConfig() if config is None else config
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


def fit_nbrdf_samples(values, directions, config: FitConfig | None = None, progress: bool = True) -> NBRDF:
    """Fits one NBRDF to scattered samples: reflectance ``(N, 3)`` at the pairs ``(wi, wo)``, as
    :func:`frenbrdf.models.reconstruct.reconstruct` takes them (e.g. a measurement in both orders of each pair,
    :func:`frenbrdf.io.sampling.truth_samples`, which a table cannot hold). ``epochs`` are passes over them;
    ``config``: as :func:`fit_nbrdf`'s."""
    config = FitConfig() if config is None else config
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
