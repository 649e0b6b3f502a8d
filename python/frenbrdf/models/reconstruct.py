"""A user's own material: encode its samples, then refine at test time.

:func:`reconstruct` (``Model.reconstruct``, ``frenbrdf reconstruct``) runs up to three stages:

0. **encode** — the set encoder's latent z of the samples (:meth:`frenbrdf.Model.encode`).
1. **latent** — z optimised on the samples with the model's training objective: the
   cos θ_i-weighted reconstruction loss in the mapped space (L1 or MSE, as the model was
   trained) + λ2 · the latent penalty; the decoder stays fixed. Each step decodes z in torch
   and takes the decoded NBRDF's gradient on the samples from the native core (the weight
   stage's passes), about twice as fast as torch alone.
2. **weights** — the decoded NBRDF's own weights optimised, starting from the decoder's
   output (a per-material fit that starts where the encoder left off), with the same
   reconstruction loss + λ1 · the weight penalty. Where the samples hold both orders of
   pairs (a measurement, which need not be reciprocal), the NBRDF learns to tell them apart
   (an ordered NBRDF, :attr:`RefineConfig.keep_order`). Runs in the native core
   (``frenbrdf._native.WeightFit``: forward, backward and Adam in one Rust loop, the steps
   of ``torch.optim.Adam``), about twice as fast as PyTorch on these small networks.

Named budgets (:data:`BUDGETS`): ``"none"`` (stage 0), ``"latent"`` (0 + 1), ``"full"``
(0 + 1 + 2). Each stage is deterministic from :attr:`RefineConfig.seed` on one machine with one thread count,
unless its wall-clock budget (:attr:`RefineConfig.seconds`) stops it first. Another thread count changes the
arithmetic at the level of bits, and ``full``'s weight stage can end elsewhere: on 19 real measurements its render
PSNR moved by 1.0 dB on average (at most 5.2 dB, at grazing angles) between one thread and two at a constant rate,
and by 1.1 dB (at most 3.7) at the falling rate, the mean over them by 0.2–0.5 dB (research/results/full-threads).

Samples come as arrays or from a file (:func:`frenbrdf.io.read_samples`): CSV or NPZ rows
``wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b`` — unit directions in the local shading frame
(z = the normal, z > 0), BRDF values in 1/sr (≥ 0, not multiplied by cos θ_i); or angle
columns ``theta_i,phi_i,theta_o,phi_o`` (radians; ``…_deg`` in degrees); or an ASTM E1392 ``.astm`` file
(:mod:`frenbrdf.io.astm`); or a MERL file.
:func:`frenbrdf.material.outputs.reconstruct_file` writes a result folder (``frenbrdf reconstruct``).

Examples
--------
>>> model = frenbrdf.Model.load("runs/frenbrdf")                        # doctest: +SKIP
>>> result = model.reconstruct(values, (wi, wo), refine="full")          # doctest: +SKIP
>>> result.nbrdf(wi, wo), result.timings, result.losses                  # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
import torch
from tqdm.auto import tqdm

from .. import _native
from ..io.sampling import bin_directions
from .adam import Adam
from .coverage import MAX_K, coverage_weights, uncovered_bins
from .hypernetwork import FrozenDecoder
from .losses import LossConfig, reconstruction_loss, samples_loss
from .nbrdf import (
    MAX_WIDTH,
    NBRDF,
    ORDER_INPUT,
    fold_edge_pairs,
    mapped_samples,
    nbrdf_coordinates,
    nbrdf_forward,
    one_torch_thread,
    pair_order,
    widen_params,
)

#: Stages of :func:`reconstruct`, in order.
STAGES = ("encode", "latent", "weights")
#: Learning-rate schedules of a refinement stage (:attr:`RefineConfig.schedule`).
SCHEDULES = ("constant", "cosine")
#: The most latents stage 1 may start from (:attr:`RefineConfig.starts`): more than any model's encoders.
MAX_STARTS = 64
#: The heaviest :attr:`RefineConfig.anchor`: beyond it the samples hardly move z at all.
MAX_ANCHOR = 100.0
#: The heaviest :attr:`RefineConfig.tie`.
MAX_TIE = 100.0
#: The pairs on the fold's edge that :attr:`RefineConfig.tie` ties (all of them, every step of stage 2).
TIE_PAIRS = 128
#: Weight steps per call of the native loop: how often stage 2 updates its progress bar and checks its seconds.
NATIVE_STEPS = 50


@dataclass
class RefineConfig:
    """How much test-time refinement :func:`reconstruct` does."""

    latent_steps: int = 0
    """Adam steps on the latent z (stage 1; 0 skips it)."""
    weight_steps: int = 0
    """Adam steps on the decoded NBRDF's weights (stage 2; 0 skips it)."""
    latent_lr: float = 1e-2
    """Adam learning rate of stage 1."""
    weight_lr: float = 1e-3
    """Adam learning rate of stage 2."""
    schedule: str = "constant"
    """Learning rate over a stage's steps: ``"constant"``, or ``"cosine"`` (from the stage's lr down to 0 at its
    last step: large steps first, then settling into the minimum a constant rate circles around)."""
    batch: int = 4096
    """Samples per step, drawn at random (from ``seed``) when there are more; all of them when fewer."""
    seconds: float | None = None
    """Wall-clock budget of *each* refinement stage: a stage stops after this many seconds even if
    steps remain (None: no limit; stage 2 looks every :data:`NATIVE_STEPS` steps). A stage stopped by time is
    no longer deterministic."""
    width: int | None = None
    """Least hidden width of the NBRDF that stage 2 refines: narrower layers of the decoded NBRDF are first widened to
    it without changing its output (:func:`frenbrdf.models.nbrdf.widen_params`), giving the weights more to fit with;
    the result is an NBRDF that wide. None: the decoder's widths (32 for the shipped model). Costs time: 48 about
    1.2×, 64 about 1.45× the whole ``full`` (research/measurements.md, "What limits full")."""
    keep_order: bool = True
    """Stage 2: where the samples hold pairs in both orders, (ω_i, ω_o) and its reverse kind (as a measurement
    sampled by :func:`frenbrdf.io.sampling.truth_samples` does), refine an ordered NBRDF
    (:attr:`frenbrdf.NBRDF.ordered`): one that may tell them apart, as a real measurement does near grazing.
    False, or samples in one order only (a MERL table's): the NBRDF stays reciprocal."""
    starts: int = 1
    """Stage 1 refines z from this many of the encoders' latents, the best-fitting first (a model with several
    encoders and ``encoder_choice="best-fit"``; one latent otherwise), and keeps the z that fits the samples best
    after its steps: another encoder's start can lead to a better minimum than the chosen one's. Stage 1 costs
    about ``starts`` times as much."""
    coverage_k: int = 0
    """Stage 1 weighs each sample's loss by how thinly the samples cover its region against random MERL bins
    (:func:`frenbrdf.models.coverage.coverage_weights`, k-NN density estimates with this k), so that a device's dense
    regions do not outweigh the rest; 0: every sample weighs alike. Stage 2 and the reported losses stay unweighted."""
    anchor: float = 0.0
    """Stage 1 holds the NBRDF near its start where the samples say nothing: a second loss, this many times as
    heavy as the samples', compares the NBRDF at random valid MERL bins with the start's decoding there, each bin
    weighted by how far it lies from every sample (:func:`frenbrdf.models.coverage.uncovered_bins`; the samples'
    cos θ_i weighting). Samples that cover the table leave it without effect; a device that sees only part of the
    domain keeps the encoder's guess for the rest instead of letting the search move it freely. 0 (the default and
    every budget's): off. Measured not to help (research/results/latent-anchor/README.md): at 0.03, through five
    device patterns, −0.53 dB [−0.78, −0.27] on 45 unseen procedural materials and −0.13 [−0.41, +0.15] on 19 real
    measurements; where no sample lies the encoder's guess is right about as often as where `latent` takes it."""
    tie: float = 0.0
    """Stage 2 ties the NBRDF's two sides of the fold's edge: its loss adds this many times the mean gap
    ``|N(a) − N(b)|`` (its square for an ``mse`` model) over :data:`TIE_PAIRS` pairs
    (:func:`frenbrdf.models.nbrdf.fold_edge_pairs`), which a reciprocal BRDF gives one value. Without it the weights
    fit each side to the samples on that side, and a render may show a faint line through each highlight where
    light, view and normal are coplanar (research/results/seam). 0 (the default and
    every budget's): off. Measured not to pay (research/results/full-tie/README.md): ``full`` at 0.1 steps across
    the edge a fifth as much at the 90th percentile in 1.07× the time, but loses 1.9 dB on 19 real measurements and
    1.1 dB on 40 tables, at grazing angles, where the pairs weigh as much as anywhere."""
    seed: int = 0
    """Seeds the mini-batches (and a widened NBRDF's new weights, and the tied pairs)."""
    progress: bool = False
    """Show a progress bar per stage."""

    def __post_init__(self):
        problems = []
        for name in ("latent_steps", "weight_steps"):
            if int(getattr(self, name)) < 0:
                problems.append(f"{name} must be ≥ 0, got {getattr(self, name)}")
        for name in ("latent_lr", "weight_lr"):  # Adam's steps are about lr in size: larger ones overflow
            if not 0 < getattr(self, name) <= 1:
                problems.append(f"{name} must lie in (0, 1], got {getattr(self, name)}")
        if self.schedule not in SCHEDULES:
            problems.append(f"schedule must be one of {SCHEDULES}, got {self.schedule!r}")
        if int(self.batch) < 1:
            problems.append(f"batch must be ≥ 1, got {self.batch}")
        counted = isinstance(self.starts, numbers.Integral) and not isinstance(self.starts, bool)
        if not (counted and 1 <= self.starts <= MAX_STARTS):
            problems.append(f"starts must be an integer from 1 to {MAX_STARTS}, got {self.starts!r}")
        counted = isinstance(self.coverage_k, numbers.Integral) and not isinstance(self.coverage_k, bool)
        if not (counted and 0 <= self.coverage_k <= MAX_K):
            problems.append(f"coverage_k must be an integer from 0 to {MAX_K}, got {self.coverage_k!r}")
        if not (isinstance(self.anchor, numbers.Real) and not isinstance(self.anchor, bool)
                and 0 <= self.anchor <= MAX_ANCHOR):
            problems.append(f"anchor must be a number from 0 to {MAX_ANCHOR:g}, got {self.anchor!r}")
        if not (isinstance(self.tie, numbers.Real) and not isinstance(self.tie, bool) and 0 <= self.tie <= MAX_TIE):
            problems.append(f"tie must be a number from 0 to {MAX_TIE:g}, got {self.tie!r}")
        elif self.tie and not self.weight_steps:
            problems.append(f"tie ties stage 2's weights: it needs weight_steps > 0, got tie {self.tie} with "
                            f"weight_steps {self.weight_steps}")
        if self.seconds is not None and not self.seconds > 0:
            problems.append(f"seconds must be positive or None, got {self.seconds}")
        if self.width is not None and not (isinstance(self.width, numbers.Integral) and 1 <= self.width <= MAX_WIDTH
                                           and self.weight_steps):
            problems.append(f"width must be None or 1 to {MAX_WIDTH} with weight_steps > 0, got {self.width} with "
                            f"weight_steps {self.weight_steps}")
        if not isinstance(self.keep_order, bool):
            problems.append(f"keep_order must be True or False, got {self.keep_order!r}")
        if problems:
            raise ValueError("invalid refinement: " + "; ".join(problems))


#: The named budgets of ``refine=``: ``latent`` optimises z only (the result stays in the latent space, so it can
#: be edited), ``full`` then fits the NBRDF's own weights, widened to 64 units, at a rate falling from 1e-2 to 0
#: (research/results/full-schedule: +0.96 dB on 19 measurements, +2.61 on 40 tables, than a constant
#: 3e-3). Each setting was chosen by a rule fixed before measuring; the measurements are in research/README.md
#: ("Test-time refinement").
BUDGETS = {
    "none": RefineConfig(),
    "latent": RefineConfig(latent_steps=600, latent_lr=3e-2, schedule="cosine"),
    "full": RefineConfig(latent_steps=100, weight_steps=1500, weight_lr=1e-2, width=64, schedule="cosine"),
}


def refine_config(refine: str | RefineConfig) -> RefineConfig:
    """A :class:`RefineConfig` from a budget name of :data:`BUDGETS`, or the config itself."""
    if isinstance(refine, RefineConfig):
        return refine
    if refine not in BUDGETS:
        raise ValueError(f"refine must be one of {tuple(BUDGETS)} or a RefineConfig, got {refine!r}")
    return dataclasses.replace(BUDGETS[refine])


@dataclass
class Reconstruction:
    """What :func:`reconstruct` found for one material."""

    z: np.ndarray
    """The latent ``(latent,)`` after stage 1 (the encoder's when stage 1 did not run)."""
    nbrdf: NBRDF
    """The material: ``model.decode(z)``, or the refined weights after stage 2."""
    timings: dict[str, float] = field(default_factory=dict)
    """Seconds per stage that ran (``encode``, ``latent``, ``weights``)."""
    losses: dict[str, float] = field(default_factory=dict)
    """Per stage that ran, the reconstruction loss (mapped space, cos θ_i-weighted, the model's L1 or MSE)
    on all given samples after it: comparable between stages."""
    steps: dict[str, int] = field(default_factory=dict)
    """Steps each refinement stage took (fewer than asked when its ``seconds`` ran out)."""
    encoder: dict = field(default_factory=dict)
    """How stage 0 chose z among the model's encoders (:meth:`frenbrdf.models.autoencoder.Encoding.summary`): which
    one and each one's loss, where the model chooses the best fit."""

    def summary(self) -> dict:
        """JSON-ready: the latent, timings, losses, steps and the encoder choice."""
        return {"z": [float(v) for v in self.z], "timings_s": self.timings, "losses": self.losses,
                "steps": self.steps, "encoder": self.encoder}


@dataclass
class _Record:
    """What the stages of :func:`reconstruct` record while they run (as :class:`Reconstruction` keeps it)."""

    timings: dict[str, float] = field(default_factory=dict)
    losses: dict[str, float] = field(default_factory=dict)
    steps: dict[str, int] = field(default_factory=dict)


@dataclass
class _Samples:
    """One material's samples as tensors: NBRDF inputs, mapped values and cos θ_i, with a leading batch of 1."""

    coords: torch.Tensor
    values: torch.Tensor
    cos_in: torch.Tensor

    def __len__(self) -> int:
        return self.coords.shape[1]


def reconstruct(model, values, directions, *, refine: str | RefineConfig = "full") -> Reconstruction:
    """Encodes one material's samples and refines the result at test time (see the module docstring).

    Parameters
    ----------
    model
        A :class:`frenbrdf.Model`.
    values
        Reflectance ``(N, 3)`` (physical units, ≥ 0).
    directions
        ``(wi, wo)``, unit vectors ``(N, 3)`` each, above the surface.
    refine
        A budget name of :data:`BUDGETS` (``"none"``, ``"latent"``, ``"full"``) or a :class:`RefineConfig`.
    """
    config = refine_config(refine)
    loss = _loss_config(model)
    mapped, coords, cos_in = mapped_samples(model.mapping, values, directions)
    wi, wo = (np.asarray(d, dtype=np.float64) for d in directions)  # checked by mapped_samples
    samples = _Samples(*(torch.from_numpy(np.asarray(a, dtype=np.float32))[None] for a in (coords, mapped, cos_in)))
    record = _Record()

    start = time.perf_counter()
    encoding = model.encoding(values, directions)
    z = torch.from_numpy(encoding.z.astype(np.float32))[None]
    record.timings["encode"] = time.perf_counter() - start
    with torch.no_grad():
        params = model.network.decoder(z)
    record.losses["encode"] = _sample_loss(params, samples, loss.kind)
    if not math.isfinite(record.losses["encode"]):
        raise ValueError("the model's decoded NBRDF is not finite on these samples before any refinement: the model "
                         "is damaged, or the samples lie far outside what it was trained on")

    if config.latent_steps:
        weighted = samples
        if config.coverage_k:  # the weights enter as a factor of cos θ_i, which multiplies each sample's error
            weights = torch.from_numpy(coverage_weights(wi, wo, config.coverage_k).astype(np.float32))[None]
            weighted = _Samples(samples.coords, samples.values, samples.cos_in * weights)
        anchors = _anchor_samples(wi, wo) if config.anchor else None
        refined = [_refine_latent(model, start, weighted, anchors, loss, config, record)
                   for start in _starts(encoding, config.starts)]
        z, record.losses["latent"] = min(refined, key=lambda pair: pair[1])  # the loss on all samples, computed once
        with torch.no_grad():
            params = model.network.decoder(z)
        if config.coverage_k:
            record.losses["latent"] = _sample_loss(params, samples, loss.kind)  # unweighted, as every stage's

    order = pair_order(wi, wo) if config.weight_steps and config.keep_order else None
    ordered = order is not None and bool(np.ptp(order) > 0)  # pairs of both orders among the samples
    if config.weight_steps:
        params = [p.detach().clone() for p in params]
        if config.width is not None:
            params = widen_params(params, config.width, torch.Generator().manual_seed(config.seed))
        if ordered and order is not None:
            # The order enters where the input was 0 for every pair: its weights go first, the output stays.
            params[0][:, :, ORDER_INPUT] = 0
            samples.coords[0, :, ORDER_INPUT] = torch.from_numpy(order.astype(np.float32))
        params = _refine_weights(params, samples, loss, config, record, ordered)
        record.losses["weights"] = _sample_loss(params, samples, loss.kind)

    nbrdf = NBRDF([p.detach() for p in params], model.mapping, ordered)  # checked: finite weights
    nbrdf(wi, wo)  # raises where its reflectance overflows
    return Reconstruction(z[0].detach().numpy().astype(np.float64), nbrdf, record.timings, record.losses, record.steps,
                          encoding.summary())


def _starts(encoding, count: int) -> list[torch.Tensor]:
    """Stage 1's starting latents ``(1, latent)``: z, then the other encoders' latents by their fit (best-fit)."""
    latents = [encoding.z]
    if encoding.losses is not None and count > 1:
        others = [index for index in np.argsort(encoding.losses, kind="stable") if index != encoding.chosen]
        latents += [encoding.latents[index] for index in others[:count - 1]]
    return [torch.from_numpy(np.asarray(latent, dtype=np.float32))[None] for latent in latents]


def _anchor_samples(wi: np.ndarray, wo: np.ndarray) -> _Samples | None:
    """:func:`~frenbrdf.models.coverage.uncovered_bins` of the samples as stage 1's anchors: NBRDF inputs and cos θ_i
    times remoteness (their values, the start's decoding, come per start); None where no bin lies far from the samples."""
    bins, remoteness = uncovered_bins(wi, wo)
    if not len(bins):
        return None
    anchor_wi, anchor_wo = bin_directions(bins)
    coords = nbrdf_coordinates(anchor_wi, anchor_wo)
    weights = np.clip(anchor_wi[:, 2], 0.0, 1.0) * remoteness
    return _Samples(*(torch.from_numpy(np.asarray(a, dtype=np.float32))[None]
                      for a in (coords, np.zeros((len(bins), 3)), weights)))


def _refine_latent(model, z: torch.Tensor, samples: _Samples, anchors: _Samples | None, loss: LossConfig,
                   config: RefineConfig, record: _Record) -> tuple[torch.Tensor, float]:
    """Stage 1 from one start: z after its steps, and the loss of its decoding on all samples. ``anchors``
    (:func:`_anchor_samples`) hold the start's decoding far from the samples, with weight ``config.anchor``.

    Each step decodes z (:class:`~frenbrdf.models.hypernetwork.FrozenDecoder`), takes the decoded NBRDF's loss
    gradient from the native core (:meth:`frenbrdf._native.WeightFit.gradient`, the weight stage's forward and
    backward passes) and carries it back to z: in torch's autograd the NBRDF's passes over thousands of samples and
    the decoder's small operations were most of a step's time (research/performance.md)."""
    decoder = model.network.decoder
    with torch.no_grad():
        start = decoder(z)
    # Only the fit's gradient is used: stage 1's penalty is on z, so no decay.
    fit, frozen = _native_fit(start, samples, [0.0] * len(start), loss.kind), FrozenDecoder(decoder)
    if anchors is not None:  # in torch: its errors start at exactly 0, where the native passes' rounding would not
        anchors = _Samples(anchors.coords, nbrdf_forward(start, anchors.coords), anchors.cos_in)
    z = z.clone().requires_grad_(True)

    def latent_step(rows: np.ndarray | None) -> float:
        """The loss on ``rows`` at z, with its gradient left in ``z.grad``."""
        weights = frozen.weights(z.detach()).numpy()
        if not np.isfinite(weights).all():
            return math.nan
        value, gradient = fit.gradient(weights, rows)
        z.grad = frozen.pullback(torch.from_numpy(gradient))
        if anchors is not None:
            held = reconstruction_loss(nbrdf_forward(decoder(z), anchors.coords), anchors.values, anchors.cos_in,
                                       loss.kind)
            z.grad += torch.autograd.grad(config.anchor * held, z)[0]
            value += config.anchor * float(held)
        return value

    with _frozen(model.network), one_torch_thread():
        latent_decay = 2 * loss.lambda_latent / z.numel()  # λ2 · latent_penalty(z) = λ2 · mean(z²)
        _optimise("latent", [z], [latent_decay], latent_step, config.latent_steps, config.latent_lr, len(samples),
                  config, record)
    z = z.detach()
    with torch.no_grad():
        return z, _sample_loss(decoder(z), samples, loss.kind)


def _native_fit(params: list[torch.Tensor], samples: _Samples, decays: list[float], kind: str):
    """A native :class:`frenbrdf._native.WeightFit` on ``samples``, shaped as the NBRDF ``params`` (with their
    leading batch of 1), with Adam's weight decay ``decays`` per tensor."""
    return _native.WeightFit([np.ascontiguousarray(p[0].numpy(), dtype=np.float32) for p in params], decays,
                             samples.coords[0].numpy(), samples.values[0].numpy(), samples.cos_in[0].numpy(), kind)


def _loss_config(model) -> LossConfig:
    """The model's training loss settings that refinement uses (LossConfig's defaults for what it lacks)."""
    kept = {"kind", "lambda_weights", "weight_penalty", "lambda_latent"}
    return LossConfig(**{key: value for key, value in model.loss.items() if key in kept})


def _weight_decays(params: list[torch.Tensor], loss: LossConfig) -> list[float]:
    """Adam's weight decay per tensor whose step is that of λ1 · :func:`~frenbrdf.models.losses.weight_penalty`:
    its gradient is 2·λ1·p / n, n the tensor's size (``per_tensor``) or all tensors' sizes together (``all``)."""
    if loss.weight_penalty == "all":
        return [2 * loss.lambda_weights / sum(p.numel() for p in params)] * len(params)
    return [2 * loss.lambda_weights / p.numel() for p in params]


def _optimise(stage: str, parameters: list[torch.Tensor], decays: list[float],
              step: Callable[[np.ndarray | None], float], steps: int, lr: float, count: int,
              config: RefineConfig, record: _Record) -> None:
    """Adam on ``parameters`` for ``steps`` steps or ``config.seconds``; records the time and steps taken.

    ``step(rows)`` returns the loss on those of the ``count`` samples (None: all of them, where they fit in one
    batch) and leaves its gradient in the parameters' ``.grad``. The stage's penalty (a mean square of each tensor,
    times λ) is not in it: it enters as Adam's weight decay, ``decays`` per tensor (its gradient 2·λ·p / n is the
    decay times p), the same steps as differentiating it for ~30 fewer small ops a step (research/performance.md)."""
    optimizer = Adam(parameters, decays)
    rates = _learning_rates(lr, steps, config.schedule)
    generator = torch.Generator().manual_seed(config.seed + STAGES.index(stage))
    start, taken = time.perf_counter(), 0
    for rate in tqdm(rates, desc=f"refine {stage}", disable=not config.progress, leave=False):
        if config.seconds is not None and time.perf_counter() - start > config.seconds:
            break
        rows = None if count <= config.batch else torch.randint(count, (config.batch,), generator=generator).numpy()
        value = step(rows)
        if not math.isfinite(value):  # finite at the start (checked), so the steps made it so
            raise _diverged(stage, taken, lr, value)
        optimizer.step(float(rate))
        taken += 1
    record.timings[stage] = record.timings.get(stage, 0.0) + time.perf_counter() - start  # summed over starts
    record.steps[stage] = record.steps.get(stage, 0) + taken


def _refine_weights(params: list[torch.Tensor], samples: _Samples, loss: LossConfig, config: RefineConfig,
                    record: _Record, ordered: bool) -> list[torch.Tensor]:
    """Stage 2 in the native loop (:class:`frenbrdf._native.WeightFit`): Adam's steps as :func:`_optimise` takes
    them, with the penalties as weight decay, over :data:`NATIVE_STEPS` steps a call; the refined tensors. ``ordered``:
    the NBRDF is ordered (the tie's pairs then are too)."""
    fit = _native_fit(params, samples, _weight_decays(params, loss), loss.kind)
    if config.tie:
        fit.tie(fold_edge_pairs(TIE_PAIRS, config.seed, ordered).astype(np.float32), config.tie)
    rates = _learning_rates(config.weight_lr, config.weight_steps, config.schedule)
    generator = torch.Generator().manual_seed(config.seed + STAGES.index("weights"))
    start, taken = time.perf_counter(), 0
    with tqdm(total=len(rates), desc="refine weights", disable=not config.progress, leave=False) as bar:
        while taken < len(rates):
            if config.seconds is not None and time.perf_counter() - start > config.seconds:
                break
            count = min(NATIVE_STEPS, len(rates) - taken)
            rows = (None if len(samples) <= config.batch else
                    torch.randint(len(samples), (count, config.batch), generator=generator).numpy())
            losses = fit.run(rates[taken:taken + count].astype(np.float32), rows)
            if not math.isfinite(losses[-1]):  # the native loop stops at the first loss that is not finite
                raise _diverged("weights", taken + len(losses) - 1, config.weight_lr, float(losses[-1]))
            taken += count
            bar.update(count)
    record.timings["weights"] = time.perf_counter() - start
    record.steps["weights"] = taken
    return [torch.from_numpy(t).reshape(p.shape) for t, p in zip(fit.tensors(), params, strict=True)]


def _learning_rates(lr: float, steps: int, schedule: str) -> np.ndarray:
    """A stage's learning rate at each step: constant, or cosine from ``lr`` towards 0 (as torch's
    CosineAnnealingLR over ``steps``)."""
    if schedule == "cosine":
        return lr * (1 + np.cos(np.pi * np.arange(steps) / steps)) / 2
    return np.full(steps, float(lr))


def _diverged(stage: str, step: int, lr: float, value: float) -> ValueError:
    """The error of a stage whose loss stopped being finite (it was at the start, checked, so the steps made it so)."""
    setting = "latent_lr" if stage == "latent" else "weight_lr"
    return ValueError(f"refinement ({stage}) diverged at step {step} with {setting} {lr:g}: the loss is {value}; try a "
                      f"smaller {setting}")


def _sample_loss(params: list[torch.Tensor], samples: _Samples, kind: str) -> float:
    """The reconstruction loss on all samples."""
    return samples_loss(params, samples.coords, samples.values, samples.cos_in, kind)


@contextmanager
def _frozen(module: torch.nn.Module):
    """The module's parameters need no gradient inside the block (only the latent is optimised)."""
    flags = [p.requires_grad for p in module.parameters()]
    module.requires_grad_(False)
    try:
        yield
    finally:
        for parameter, flag in zip(module.parameters(), flags, strict=True):
            parameter.requires_grad_(flag)
