"""Each training step's batch: the sampled tables, and augmented materials in place of some.

:class:`BatchDrawer` draws a step's context and query samples (:class:`TrainingBatch`) as the
paper does, then, as :class:`~frenbrdf.training.config.AugmentConfig` says, replaces some
materials of the batch (docs/data.md gives the physical argument for each):

- a *mix* t·a + (1 − t)·b of two training tables, at bins valid in both: each mapped value is
  un-mapped to reflectance with f_ref at its bin, mixed, and mapped again;
- a *gained* table g_c · f, the gains scaled so that the material's largest directional albedo
  (:func:`frenbrdf.data.folders.max_directional_albedo`, computed once in ``prepare``) stays ≤ 1;
  some of them (``hue_turn``) with their colour first turned about the grey axis (:func:`hue_turn`), by an
  angle that changes with direction where ``hue_shift`` says (:class:`HueTurn`);
- a *procedural* material (:mod:`.procedural`), evaluated exactly at the sampled bins, with
  its L_fre truth evaluated exactly at the SHT nodes.

Context and query samples of one material are drawn together, so both describe the same
material. Every random choice comes from the training loop's generator: the same seed gives
the same batches, and a resumed run continues the same sequence. With augmentation off the
generator is used exactly as before it existed.

With :class:`~frenbrdf.training.config.SamplingConfig` set (anything but the ``paper`` preset), each
material's context samples, augmented ones included, come from a sampling pattern
(:mod:`frenbrdf.training.patterns`), and each step's count from ``sampling.counts``; the query samples stay random
valid bins. With the ``paper`` sampling the generator is used exactly as before that option existed.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import torch

from ..data.folders import SampleBatch
from ..io.merl import merl_above_horizon
from ..models.nbrdf import bin_geometry
from .config import TrainConfig
from .patterns import PatternSampler
from .procedural import NodeTruth, draw_procedural, values_at_bins

#: What each material of a batch is.
TABLE, MIX, GAIN, PROCEDURAL = range(4)


@dataclass
class TrainingBatch:
    """The samples of one step's materials and, with L_fre, their true coefficients."""

    context: SampleBatch
    query: SampleBatch
    truth: torch.Tensor | None = None
    """``(B, S, 3, ncoeff)``, or None without L_fre."""
    truth_mask: torch.Tensor | None = None
    """``(B,)`` bool: the materials whose truth is known (None: all). Mixes and gained tables have
    none: L_fre leaves them out."""
    roles: np.ndarray | None = None
    """``(B,)``: what each material is (:data:`TABLE`, :data:`MIX`, :data:`GAIN`, :data:`PROCEDURAL`);
    None without augmentation."""

    def take(self, materials: slice) -> TrainingBatch:
        """The part of the batch for some of the materials (a rank's share)."""
        return TrainingBatch(self.context.take(materials), self.query.take(materials),
                             None if self.truth is None else self.truth[materials],
                             None if self.truth_mask is None else self.truth_mask[materials],
                             None if self.roles is None else self.roles[materials])

    def to(self, device) -> TrainingBatch:
        return TrainingBatch(self.context.to(device), self.query.to(device),
                             None if self.truth is None else self.truth.to(device),
                             None if self.truth_mask is None else self.truth_mask.to(device), self.roles)


class BatchDrawer:
    """Draws training batches of a run's prepared data (:class:`~frenbrdf.training.PreparedData`).

    Parameters
    ----------
    cfg
        The run's config: sample counts, ``context_jitter``, ``augment``, ``sampling``.
    data
        The prepared data (its bank, mapping, truth and, with gains, albedos).
    with_truth
        Whether batches carry L_fre's true coefficients.
    """

    def __init__(self, cfg: TrainConfig, data, with_truth: bool):
        self.cfg, self.data, self.augment = cfg, data, cfg.augment
        self.with_truth = with_truth and data.truth is not None
        #: The sampling patterns and their setups, or None for the paper's sampling (random valid bins).
        self.patterns = (None if cfg.sampling.paper else
                         PatternSampler(cfg.sampling, cfg.sampling.most_context(cfg.context_samples), cfg.seed))
        if not self.augment.active:
            return
        self.reference = torch.from_numpy(np.ascontiguousarray(data.mapping.reference_bins().T, dtype=np.float32))
        if self.augment.procedural > 0:
            above = torch.from_numpy(merl_above_horizon().reshape(-1))
            self.above_horizon, self.above_mask = torch.nonzero(above).squeeze(1), above
            self.node_truth = NodeTruth(cfg.loss.frequency, data.mapping) if self.with_truth else None
        if self.augment.gain > 0 and data.albedo is None:
            raise ValueError("gain augmentation needs the materials' albedos: prepare the data with this config")

    def context_count(self, generator: torch.Generator) -> int:
        """This step's number of context samples: log-uniform in ``sampling.counts``, or drawn from [jitter · N, N]
        with ``context_jitter``, else N = ``context_samples``."""
        counts = self.cfg.sampling.counts
        if counts is not None:
            low, high = math.log(counts[0]), math.log(counts[1] + 1)
            u = float(torch.rand(1, generator=generator, dtype=torch.float64))
            return min(counts[1], int(math.exp(low + u * (high - low))))
        n = self.cfg.context_samples
        if self.cfg.context_jitter == 0:
            return n
        low = max(1, math.ceil(self.cfg.context_jitter * n))
        return int(torch.randint(low, n + 1, (1,), generator=generator))

    def draw(self, batch: list[int], generator: torch.Generator) -> TrainingBatch:
        """The batch of training materials ``batch`` (bank indices), some replaced by augmented ones."""
        n_context, n_query = self.context_count(generator), self.cfg.query_samples
        patterns: list[str | None] = [None] * len(batch)
        if self.patterns is None:
            context = self.data.bank.sample(batch, n_context, generator)
        else:
            patterns = list(self.patterns.choose(len(batch), generator))
            context = self.pattern_context(batch, patterns, n_context, generator)
        query = self.data.bank.sample(batch, n_query, generator)
        truth = self.data.truth[batch] if self.with_truth else None
        if not self.augment.active:
            return TrainingBatch(context, query, truth)
        roles = self.roles(len(batch), generator)
        geometry = bin_geometry()
        for slot in np.flatnonzero(roles != TABLE):
            if roles[slot] == PROCEDURAL:
                material = draw_procedural(generator)
                bins = self.role_bins(self.above_horizon, lambda: self.above_mask, n_context + n_query, generator,
                                      patterns[slot])
                values = values_at_bins(material, bins, self.data.mapping, self.reference[bins])
                if truth is not None and self.node_truth is not None:
                    truth[slot] = self.node_truth.coefficients(material)
            elif roles[slot] == MIX:
                bins, values = self.mixed(batch[slot], n_context + n_query, generator, patterns[slot])
            else:
                bins, values = self.gained(batch[slot], n_context + n_query, generator, patterns[slot])
            for samples, part in ((context, slice(0, n_context)), (query, slice(n_context, None))):
                samples.coords[slot] = geometry.half_diff[bins[part]]
                samples.values[slot] = values[part]
                samples.cos_in[slot] = geometry.cos_in[bins[part]]
        mask = torch.from_numpy((roles == TABLE) | (roles == PROCEDURAL)) if truth is not None else None
        return TrainingBatch(context, query, truth, mask, roles)

    def pattern_context(self, batch: list[int], patterns: list, n: int, generator: torch.Generator) -> SampleBatch:
        """The context samples of each table of ``batch`` read through its pattern, ``n`` each."""
        assert self.patterns is not None
        bank = self.data.bank
        bins = torch.stack([self.patterns.bins(name, bank.valid_bins(material), bank.valid[material], n, generator)
                            for material, name in zip(batch, patterns, strict=True)])
        return bank.at_bins(batch, bins)

    def role_bins(self, valid_bins: torch.Tensor, valid, n: int, generator: torch.Generator,
                  pattern: str | None) -> torch.Tensor:
        """``n`` bins of an augmented material: its context bins, then its query bins. Without a pattern (or with
        ``merl-bins``) all are random ``valid_bins``, as ever; with one, the context bins (``n`` − ``query_samples``)
        are read through it where ``valid()`` (bool ``(N_BINS,)``, computed only then) marks the material's bins."""
        if pattern is None or pattern == "merl-bins" or self.patterns is None:
            return valid_bins[torch.randint(len(valid_bins), (n,), generator=generator)]
        n_query = self.cfg.query_samples
        context = self.patterns.bins(pattern, valid_bins, valid(), n - n_query, generator)
        return torch.cat([context, valid_bins[torch.randint(len(valid_bins), (n_query,), generator=generator)]])

    def roles(self, n: int, generator: torch.Generator) -> np.ndarray:
        """What each of ``n`` batch materials becomes: procedural, mix, gain or table, independently."""
        u = torch.rand(n, generator=generator, dtype=torch.float64).numpy()
        a = self.augment
        bounds = np.cumsum([a.procedural, a.mix, a.gain])
        return np.select([u < bounds[0], u < bounds[1], u < bounds[2]], [PROCEDURAL, MIX, GAIN], TABLE)

    def reflectance(self, material: int, bins: torch.Tensor) -> torch.Tensor:
        """A bank material's reflectance ``(n, 3)`` at bins (its mapped values un-mapped)."""
        return self.data.mapping.inverse(self.data.bank.mapped[material, bins], self.reference[bins])

    def mixed(self, a: int, n: int, generator: torch.Generator,
              pattern: str | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """Bins and mapped values of t·a + (1 − t)·b, with b another training material and t ~ U(0, 1); the
        context part of the bins read through ``pattern`` (:meth:`role_bins`)."""
        n_train = self.data.n_train
        b = (a + 1 + int(torch.randint(n_train - 1, (1,), generator=generator))) % n_train if n_train > 1 else a
        t = float(torch.rand(1, generator=generator, dtype=torch.float64))
        valid = self.data.bank.valid
        common = self.data.bank.valid_bins(a) if torch.equal(valid[a], valid[b]) else torch.nonzero(
            valid[a] & valid[b]).squeeze(1)
        if len(common) == 0:
            raise ValueError(f"materials {self.data.bank.names[a]} and {self.data.bank.names[b]} share no valid bin")
        bins = self.role_bins(common, lambda: valid[a] & valid[b], n, generator, pattern)
        mix = t * self.reflectance(a, bins) + (1 - t) * self.reflectance(b, bins)
        return bins, self.data.mapping.forward(mix, self.reference[bins])

    def gained(self, a: int, n: int, generator: torch.Generator,
               pattern: str | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """Bins and mapped values of material ``a`` in another colour: its hue turned (for a share
        ``hue_turn`` of them, by an angle that may change with direction: :class:`HueTurn`), then per-channel gains
        (:func:`draw_gains`); the context part of the bins read through ``pattern`` (:meth:`role_bins`)."""
        turn = self.draw_turn(generator)
        # A turned colour's channel is at most the turn's |row| times the channels: so is its albedo.
        albedo = self.data.albedo[a] if turn is None else turn.largest() @ self.data.albedo[a]
        gains = draw_gains(albedo, self.augment.gain_range, generator)
        bins = self.role_bins(self.data.bank.valid_bins(a), lambda: self.data.bank.valid[a], n, generator, pattern)
        colours = self.reflectance(a, bins)
        if turn is not None:
            colours = turn.apply(colours, bin_geometry().half_diff[bins]).clamp_min(0)
        return bins, self.data.mapping.forward(gains * colours, self.reference[bins])

    def draw_turn(self, generator: torch.Generator) -> HueTurn | None:
        """A hue turn for a gained table, or None; draws nothing when ``hue_turn`` is 0, and no change with angle
        when ``hue_shift`` is 0 (earlier runs' batches, bit for bit)."""
        if self.augment.hue_turn == 0:
            return None
        chance, angle = torch.rand(2, generator=generator, dtype=torch.float64).tolist()
        if chance >= self.augment.hue_turn:
            return None
        shift_h = shift_d = 0.0
        if self.augment.hue_shift > 0:
            u_h, u_d = torch.rand(2, generator=generator, dtype=torch.float64).tolist()
            shift_h, shift_d = ((2 * u - 1) * self.augment.hue_shift for u in (u_h, u_d))
        return HueTurn(2 * math.pi * angle, 2 * math.pi * shift_h, 2 * math.pi * shift_d)


@dataclass(frozen=True)
class HueTurn:
    """A turn of colour about the grey axis whose angle changes with direction:
    ``angle + shift_h · θ_h / 90° + shift_d · θ_d / 90°`` (radians), so that the hue moves from the highlight
    outwards and towards grazing, as it does on thin films and colour-shift wraps. With both shifts 0 it is one
    :func:`hue_turn` for every direction."""

    angle: float
    shift_h: float = 0.0
    shift_d: float = 0.0

    @property
    def shifts(self) -> bool:
        return self.shift_h != 0 or self.shift_d != 0

    @functools.cached_property
    def plain(self) -> torch.Tensor:
        """The ``(3, 3)`` turn by ``angle`` alone."""
        return hue_turn(self.angle)

    def angles(self, coords: torch.Tensor) -> torch.Tensor:
        """The turn's angle ``(n,)`` at NBRDF inputs ``(n, 6)`` (H then D: cos θ_h and cos θ_d are their z)."""
        theta_h, theta_d = (torch.arccos(coords[:, axis].double().clamp(-1, 1)) / (math.pi / 2) for axis in (2, 5))
        return self.angle + self.shift_h * theta_h + self.shift_d * theta_d

    def apply(self, colours: torch.Tensor, coords: torch.Tensor) -> torch.Tensor:
        """``colours`` ``(n, 3)`` turned by the angle at each of the NBRDF inputs ``coords`` ``(n, 6)``."""
        if not self.shifts:
            return colours @ self.plain.T
        turns = hue_turns(self.angles(coords))
        return torch.einsum("nij,nj->ni", turns, colours.double()).to(colours.dtype)

    def largest(self, steps: int = 33) -> torch.Tensor:
        """``(3, 3)``: each entry's largest magnitude over the angles the turn takes (sampled in ``steps``), so that
        ``largest() @ albedo`` bounds the turned material's albedo per channel."""
        if not self.shifts:
            return self.plain.abs()
        low = self.angle + min(self.shift_h, 0.0) + min(self.shift_d, 0.0)
        high = self.angle + max(self.shift_h, 0.0) + max(self.shift_d, 0.0)
        return hue_turns(torch.linspace(low, high, steps, dtype=torch.float64)).abs().amax(dim=0).float()


def hue_turn(angle: float) -> torch.Tensor:
    """The ``(3, 3)`` rotation of linear RGB about the grey axis by ``angle`` (radians, Rodrigues' formula):
    greys are kept, and a third of a turn takes red to green to blue."""
    cos, sin = (torch.tensor(value, dtype=torch.float64) for value in (math.cos(angle), math.sin(angle)))
    return _rodrigues(cos, sin).float()


def hue_turns(angles: torch.Tensor) -> torch.Tensor:
    """:func:`hue_turn` for each of ``angles`` ``(n,)``: ``(n, 3, 3)``, float64."""
    angles = angles.double()[:, None, None]
    return _rodrigues(torch.cos(angles), torch.sin(angles))


def _rodrigues(cos: torch.Tensor, sin: torch.Tensor) -> torch.Tensor:
    """The turn about the grey axis with these cosines and sines (broadcast against ``(3, 3)``), float64."""
    k = torch.full((3,), 1 / math.sqrt(3), dtype=torch.float64)
    cross = torch.tensor([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]], dtype=torch.float64)
    turn = cos * torch.eye(3, dtype=torch.float64) + sin * cross
    return turn + (1 - cos) * torch.outer(k, k)


def draw_gains(albedo: torch.Tensor, gain_range: tuple[float, float], generator: torch.Generator) -> torch.Tensor:
    """Per-channel gains ``(3,)``: log-uniform in ``gain_range``, then all scaled by one factor ≤ 1 so
    that ``max_c g_c · albedo_c ≤ 1`` (the colour change is kept, the brightness capped)."""
    low, high = math.log(gain_range[0]), math.log(gain_range[1])
    gains = torch.exp(low + (high - low) * torch.rand(3, generator=generator, dtype=torch.float64)).float()
    brightest = float((gains * albedo).max())
    return gains / brightest if brightest > 1 else gains
