"""Sampling patterns in training: each pattern's device setups as MERL bins, drawn once per run.

With :class:`~frenbrdf.training.config.SamplingConfig` (docs/data.md, "Sampling patterns"), each material of a
step is read by the encoder through one pattern of :mod:`frenbrdf.io.patterns`: a gonioreflectometer's curves, a
photograph's lines, the highlight only. The training tables hold values at the MERL bins, so a pattern's pair
takes the value of its nearest bin (:func:`nearest_bins`, the bin :func:`frenbrdf.io.merl.merl_lookup` with
``method="nearest"`` reads) and the encoder is given that bin's coordinates, as for every other sample.

A pattern does not depend on the material, only on which of its bins hold a measurement; so
:class:`PatternPool` draws :data:`SETUPS` device setups of each pattern once (from the run's seed), each as many
pairs as a step may ask for, and keeps their bins. A step then costs a gather: one setup of the material's
pattern, its bins the material holds, as many of them as the step's count, drawn without replacement (with
replacement where the material holds fewer). Which setup and which of its bins come from the training generator,
so the same seed gives the same batches and a resumed run continues the same sequence.

``merl-bins`` is not pooled: it is the paper's draw itself, random valid bins of the material.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from ..io.merl import N_BINS, SHAPE
from ..io.patterns import PATTERNS, sample_pattern
from ..numerics.coords import directions_to_rusinkiewicz
from .config import SamplingConfig

#: Device setups drawn per pattern and run: each a pattern call of its own (its own lights, incidence angles,
#: camera), so that training sees many devices of a kind. 64 setups of 4,000 pairs of the nine pooled patterns
#: hold 9 MB and take about a second to draw.
SETUPS = 64
#: Setups tried for a material before a pattern is given up on: where one holds none of the material's bins.
_TRIES = 8


def nearest_bins(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The flat index of each pair's nearest MERL bin (rounded continuous index, as the nearest lookup of
    :func:`frenbrdf.io.merl.merl_lookup` takes; φ_h dropped, φ_d folded by reciprocity), int64 ``(n,)``."""
    angles = directions_to_rusinkiewicz(wi, wo)
    quarter = math.pi / 2
    n_h, n_d, n_p = SHAPE[1:]
    h = np.rint(np.sqrt(np.clip(angles[:, 0], 0, quarter) / quarter) * n_h).clip(0, n_h - 1)
    d = np.rint(np.clip(angles[:, 2], 0, quarter) / quarter * n_d).clip(0, n_d - 1)
    p = np.rint(np.mod(angles[:, 3], math.pi) / math.pi * n_p) % n_p
    return (p + n_p * (d + n_d * h)).astype(np.int64)


class PatternPool:
    """:data:`SETUPS` device setups of one pattern, ``size`` pairs each, as their nearest bins.

    Parameters
    ----------
    name
        A pattern of :data:`frenbrdf.io.patterns.PATTERNS` other than ``merl-bins``.
    size
        Pairs per setup: the most context samples a step draws.
    rng
        Draws the setups.
    """

    def __init__(self, name: str, size: int, rng: np.random.Generator):
        self.name = name
        setups = [nearest_bins(*sample_pattern(name, size, rng)) for _ in range(SETUPS)]
        #: ``(SETUPS, size)`` int64: each setup's bins, in the pattern's order.
        self.bins = torch.from_numpy(np.stack(setups))

    def draw(self, valid: torch.Tensor, n: int, generator: torch.Generator) -> torch.Tensor:
        """``n`` bins ``(n,)`` of one setup where ``valid`` (bool ``(N_BINS,)``, the material's measured bins) holds:
        a random setup, then ``n`` of its valid bins without replacement (with, where it has fewer)."""
        for _ in range(_TRIES):
            setup = self.bins[int(torch.randint(len(self.bins), (1,), generator=generator))]
            held = setup[valid[setup]]
            if len(held) >= n:
                return held[torch.randperm(len(held), generator=generator)[:n]]
            if len(held) > 0:
                return held[torch.randint(len(held), (n,), generator=generator)]
        raise ValueError(f"the material holds a measurement at none of the bins of {_TRIES} {self.name!r} setups: "
                         "leave that pattern out of sampling.patterns for these materials")


class PatternSampler:
    """The patterns of a :class:`~frenbrdf.training.config.SamplingConfig`: which one each material of a step
    takes, and its bins.

    Parameters
    ----------
    sampling
        The patterns and their weights.
    size
        The most context samples a step draws (the pools' setup size).
    seed
        The run's seed: each pattern's setups are drawn from it (and the pattern's place in
        :data:`~frenbrdf.io.patterns.PATTERNS`), the same for the same seed, a resume included.
    """

    def __init__(self, sampling: SamplingConfig, size: int, seed: int):
        chosen = {name: weight for name, weight in sampling.patterns.items() if weight > 0}
        self.names = list(chosen)
        weights = torch.tensor(list(chosen.values()), dtype=torch.float64)
        self.bounds = torch.cumsum(weights / weights.sum(), 0)
        order = list(PATTERNS)
        self.pools = {name: PatternPool(name, size, np.random.default_rng([seed, order.index(name)]))
                      for name in self.names if name != "merl-bins"}

    def choose(self, n: int, generator: torch.Generator) -> list[str]:
        """The patterns of ``n`` materials, each drawn independently with the configured chances."""
        u = torch.rand(n, generator=generator, dtype=torch.float64)
        picks = torch.searchsorted(self.bounds, u, right=True).clamp_max(len(self.names) - 1)
        return [self.names[i] for i in picks.tolist()]

    def bins(self, name: str, valid_bins: torch.Tensor, valid: torch.Tensor | None, n: int,
             generator: torch.Generator) -> torch.Tensor:
        """``n`` context bins of a material read through the pattern ``name``: random ``valid_bins`` (its measured
        bins) for ``merl-bins``, as the paper draws; else a setup of the pattern at the bins ``valid``
        (bool ``(N_BINS,)``; None: the bins of ``valid_bins``) marks."""
        if name == "merl-bins":
            return valid_bins[torch.randint(len(valid_bins), (n,), generator=generator)]
        if valid is None:
            valid = torch.zeros(N_BINS, dtype=torch.bool)
            valid[valid_bins] = True
        return self.pools[name].draw(valid, n, generator)
