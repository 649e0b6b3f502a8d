"""The training config, and the presets of :mod:`frenbrdf.presets` laid over it."""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..configs import MAX_SEED, from_dict, merge, to_dict
from ..io.jsonfile import read_json
from ..io.merl import N_BINS
from ..io.patterns import PATTERNS
from ..models.autoencoder import ModelConfig
from ..models.encoder import SAMPLE_SIZE, SCORE_HIDDEN, EncoderConfig
from ..models.losses import LossConfig
from ..models.nbrdf import N_INPUTS, N_OUTPUTS
from ..presets import (
    METHODS,
    SELECTION_RULES,
    augmentation_overrides,
    check_method,
    frequency_overrides,
    sampling_overrides,
    training_overrides,
)

#: What a run's validation context samples may be read through (``TrainConfig.validate_through``).
VALIDATION_CONTEXTS = ("merl-bins", "sampling")
#: The largest training config file read (one is about 2 kB).
MAX_CONFIG_BYTES = 1 << 20
#: The most memory a training step may hold (:meth:`TrainConfig.step_bytes`): what every accepted config runs in on
#: a machine of a few GB. The presets take 120–190 MB.
MAX_STEP_BYTES = 2 << 30


def selection_score(entry: dict, rule: str) -> float | None:
    """What ``rule`` minimises in a history entry: the validation L_rec (``"loss"``) or minus the validation
    render PSNR (``"psnr"``); None for an epoch that rule cannot judge (not rendered, or untrained)."""
    if entry["epoch"] < 0:
        return None
    if rule == "loss":
        return entry["val_rec"]
    if "val_psnr" not in entry:
        return None
    # JSON holds no infinity: a render equal to its truth (PSNR ∞) is written as null (frenbrdf.io.atomic.json_text).
    return -math.inf if entry["val_psnr"] is None else -entry["val_psnr"]


#: The most turns of hue a material's colour may go through from θ = 0 to 90° (:attr:`AugmentConfig.hue_shift`).
MAX_HUE_SHIFT = 4.0


@dataclass
class AugmentConfig:
    """Materials the training batches hold beyond the tables (docs/data.md). The defaults are the
    ``augmented`` preset of :data:`frenbrdf.presets.AUGMENTATION` (mixes and colour gains, chosen by
    measurement: research/colour.md); ``paper`` is the paper's protocol, the training tables only.

    Each material of a batch is, independently, procedural with probability ``procedural``,
    else a mix with probability ``mix``, else a gained table with probability ``gain``, else a
    training table as drawn. Validation and test materials are never augmented. L_fre
    (FreNBRDF) is computed for tables and procedural materials only: mixes and gained tables
    are masked out of it, since their true coefficients are not those of any cached table.
    """

    mix: float = 0.25
    """Fraction of batch materials replaced by t·a + (1 − t)·b of two training tables (t ~ U(0, 1)),
    mixed in reflectance at bins valid in both."""
    gain: float = 0.5
    """Fraction of batch materials given per-channel gains (a change of colour and brightness)."""
    gain_range: tuple[float, float] = (0.5, 2.0)
    """Each channel's gain is drawn log-uniform in this range, then all three are scaled down
    together where needed so that the material's albedo stays ≤ 1."""
    hue_turn: float = 0.0
    """Fraction of the gained tables whose colour is first turned about the grey axis by an angle drawn
    uniformly (:func:`frenbrdf.training.augment.hue_turn`): a red car paint becomes a yellow or a blue one,
    greys stay grey. Channels the turn takes below 0 are clipped to 0."""
    hue_shift: float = 0.0
    """With hue turns: how far, in turns, a turn may change with angle. Each turned table's angle becomes
    a + s_h · θ_h / 90° + s_d · θ_d / 90°, with s_h, s_d drawn uniformly in [−hue_shift, hue_shift] turns: a
    material whose colour shifts from the highlight outwards and towards grazing, as thin films, interference
    pigments and colour-shift wraps do (:class:`frenbrdf.training.augment.HueTurn`). 0 (the default):
    one angle for all directions, drawn exactly as before this option."""
    procedural: float = 0.0
    """Fraction of batch materials drawn afresh every step from the analytic families of
    :mod:`frenbrdf.data.synth` and evaluated exactly at the sampled bins."""
    preset: str = "augmented"
    """The :data:`frenbrdf.presets.AUGMENTATION` entry these values came from (set by
    :func:`config_for`; "custom" for values set by hand)."""

    def __post_init__(self):
        low_high = tuple(float(g) for g in self.gain_range)
        problems = []
        for name in ("mix", "gain", "procedural", "hue_turn"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                problems.append(f"{name} must lie in [0, 1], got {value}")
        if self.mix + self.gain + self.procedural > 1.0 + 1e-9:
            problems.append(f"mix + gain + procedural must be ≤ 1, got {self.mix + self.gain + self.procedural:g}")
        if self.hue_turn > 0 and self.gain == 0:
            problems.append(f"hue_turn {self.hue_turn:g} turns gained tables, but gain is 0: there are none")
        if not 0.0 <= self.hue_shift <= MAX_HUE_SHIFT:
            problems.append(f"hue_shift must lie in [0, {MAX_HUE_SHIFT}] turns, got {self.hue_shift}")
        elif self.hue_shift > 0 and self.hue_turn == 0:
            problems.append(f"hue_shift {self.hue_shift:g} changes hue turns with angle, but hue_turn is 0: there are none")
        if len(low_high) != 2 or not (0 < low_high[0] <= low_high[1] and math.isfinite(low_high[1])):
            problems.append(f"gain_range must be two finite numbers 0 < low ≤ high, got {low_high}")
        if problems:
            raise ValueError("invalid augment config: " + "; ".join(problems))
        self.gain_range = (low_high[0], low_high[1])

    @property
    def active(self) -> bool:
        """Whether any batch material may be augmented."""
        return self.mix + self.gain + self.procedural > 0


#: The most context samples a step may draw with :attr:`SamplingConfig.counts` (the most a device gives:
#: :data:`frenbrdf.io.patterns.SENSIBLE_COUNTS`).
MAX_PATTERN_COUNT = 20_000


def _paper_patterns() -> dict[str, float]:
    return {"merl-bins": 1.0}


@dataclass
class SamplingConfig:
    """How each training step draws the samples the encoder reads (docs/data.md, "Sampling patterns"). The
    defaults are the ``paper`` preset of :data:`frenbrdf.presets.SAMPLING`: random valid MERL bins,
    ``context_samples`` of them, as the paper and every earlier run drew them.

    Each material of a step takes one pattern of :data:`frenbrdf.io.patterns.PATTERNS`, drawn with the chances
    ``patterns`` gives, and its context samples are that pattern's pairs at the material's nearest bins
    (:mod:`frenbrdf.training.patterns`). The query samples, at which the loss compares, stay random valid bins
    (the loss measures the whole material); so do validation's context samples (``context_samples`` of them), so
    that validation losses stay comparable between runs.
    """

    patterns: dict[str, float] = field(default_factory=_paper_patterns)
    """Pattern name → its weight (≥ 0; the weights need not sum to 1, at least one is > 0)."""
    counts: tuple[int, int] | None = None
    """``(low, high)``: each step's number of context samples, drawn log-uniformly in low … high (one count for
    every material of the step); None: ``context_samples`` (and ``context_jitter``), as ever."""
    preset: str = "paper"
    """The :data:`frenbrdf.presets.SAMPLING` entry these values came from (set by :func:`config_for`; "custom"
    for values set by hand)."""

    def __post_init__(self):
        problems = []
        if not isinstance(self.patterns, dict) or not self.patterns:
            problems.append(f"patterns must map pattern names to weights, at least one, got {self.patterns!r}")
        else:
            unknown = [name for name in self.patterns if name not in PATTERNS]
            if unknown:
                problems.append(f"unknown pattern(s) {unknown}; the patterns are {', '.join(PATTERNS)}")
            weights = list(self.patterns.values())
            if not all(isinstance(w, (int, float)) and not isinstance(w, bool) and math.isfinite(w) and w >= 0
                       for w in weights):
                problems.append(f"pattern weights must be finite numbers ≥ 0, got {self.patterns}")
            elif sum(weights) <= 0:
                problems.append(f"at least one pattern weight must be > 0, got {self.patterns}")
        if self.counts is not None:
            counts = tuple(self.counts)
            if (len(counts) != 2 or not all(isinstance(c, numbers.Integral) and not isinstance(c, bool) for c in counts)
                    or not 1 <= counts[0] <= counts[1] <= MAX_PATTERN_COUNT):
                problems.append(f"counts must be two whole numbers 1 ≤ low ≤ high ≤ {MAX_PATTERN_COUNT:,}, or None, "
                                f"got {self.counts!r}")
            else:
                self.counts = (int(counts[0]), int(counts[1]))
        if problems:
            raise ValueError("invalid sampling config: " + "; ".join(problems))
        self.patterns = {name: float(weight) for name, weight in self.patterns.items()}

    @property
    def paper(self) -> bool:
        """Whether steps draw as the paper does (random valid bins, ``context_samples`` of them): the batches,
        and the generator's use, are exactly those of runs from before this option."""
        return self.counts is None and all(w == 0 for name, w in self.patterns.items() if name != "merl-bins")

    def most_context(self, context_samples: int) -> int:
        """The most context samples a step draws."""
        return context_samples if self.counts is None else self.counts[1]


def _score_floats(encoder: EncoderConfig) -> int:
    """Floats per sample that attention pooling's score network keeps for the backward pass: its hidden layer and
    ReLU, its scores and their softmax (none for the other poolings)."""
    return 2 * SCORE_HIDDEN + 2 * encoder.attention_heads if encoder.pooling == "attention" else 0


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
    holdout: tuple[str, ...] = ()
    """Glob patterns over material names (e.g. ``"*fabric*"``): the matching materials are the
    test split, the others are split into train/validation by ``split``'s first two fractions."""
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
    weight_decay: float = 0.0
    """Decoupled weight decay (AdamW) of the network's parameters; 0: plain Adam."""
    context_jitter: float = 0.0
    """Each step's context sample count is drawn uniformly from [jitter · context_samples,
    context_samples]; 0: always ``context_samples``."""
    patience: int = 0
    """Stop when the selection measure (``select``) has not improved for this many epochs; 0: never."""
    lr_plateau: int = 0
    """Halve the learning rate each time the selection measure has gone this many epochs without improving
    (so training settles instead of stopping on noise; pair it with a larger ``patience``); 0: never."""
    render_every: int = 0
    """Every this many epochs (and at the last), encode each validation material from 4000 samples of its
    table, decode and render it as ``frenbrdf evaluate`` does, and log the mean render PSNR and ΔE in the
    history (``val_psnr``, ``val_delta_e``); 0: never. The tables are read and rendered once; each time then
    costs about 0.03 s per material at 64²."""
    render_resolution: int = 64
    """Render size of those validation renders."""
    validate_through: str = "merl-bins"
    """The validation loss's context samples: ``"merl-bins"``, random valid bins (the paper's, and every run's
    before this field), or ``"sampling"``, each validation table read through a pattern drawn from ``sampling``
    (from a fixed seed, the same every epoch), so that ``best.pt`` and early stopping judge the reading the run
    trains for (an encoder for device patterns, say). The query samples stay random bins."""
    select: str = "loss"
    """What picks ``best.pt`` (and stops early): ``"loss"``, the lowest validation reconstruction loss
    (every epoch), or ``"psnr"``, the highest validation render PSNR (needs ``render_every``). With
    ``render_every`` the other rule's pick is kept too, as ``best-loss.pt`` or ``best-psnr.pt``."""
    decoder_from: str = ""
    """A trained model whose decoder and mapping this run takes over, frozen, so that only the encoder trains:
    a run folder, a checkpoint, a packed model's folder or ``"pretrained"`` (docs/usage.md, "Starting from a
    trained model").
    Its latent size, decoder and NBRDF must be this config's. With ``init_from`` too, the encoder starts from
    that model's instead of a fresh initialisation. Empty: the whole autoencoder trains."""
    init_from: str = ""
    """A trained model of this run's model config whose weights and mapping this run starts from (fine-tuning,
    e.g. on data with new materials): a run folder, a checkpoint, a packed model's folder or ``"pretrained"``.
    Everything trains, unless ``decoder_from`` is given too: then the decoder and mapping are that model's,
    frozen, and only the encoder, started from this one's, trains (an encoder fine-tuned for new sampling).
    Empty: a fresh initialisation from ``seed``."""
    device: str = "cpu"
    """``"cpu"``, ``"cuda"`` or ``"auto"``."""
    cache_dir: str = ""
    """Cache of true SH coefficients (default: ``$FRENBRDF_CACHE`` or ``~/.cache/frenbrdf``)."""
    progress: bool = True
    """Show progress bars."""
    model: ModelConfig = field(default_factory=ModelConfig)
    loss: LossConfig = field(default_factory=LossConfig)
    augment: AugmentConfig = field(default_factory=AugmentConfig)
    sampling: SamplingConfig = field(default_factory=SamplingConfig)

    def __post_init__(self):
        problems = []
        if self.method not in METHODS:
            problems.append(f"method must be one of {tuple(METHODS)}, got {self.method!r}")
        for name in ("epochs", "batch_materials", "context_samples", "query_samples"):
            if int(getattr(self, name)) < 1:
                problems.append(f"{name} must be ≥ 1, got {getattr(self, name)}")
        for name in ("context_samples", "query_samples"):  # drawn per material per step: a table has no more bins
            if int(getattr(self, name)) > N_BINS:
                problems.append(f"{name} must be ≤ {N_BINS} (the bins of a MERL table), got {getattr(self, name)}")
        if not 0 <= int(self.seed) <= MAX_SEED:
            problems.append(f"seed must lie in 0 … {MAX_SEED}, got {self.seed}")
        if len(self.split) != 3 or not all(0 <= f <= 1 for f in self.split) or not math.isclose(sum(self.split), 1):
            problems.append(f"split must be three fractions in [0, 1] summing to 1, got {tuple(self.split)}")
        if not 0 < self.lr <= 1:
            problems.append(f"lr must lie in (0, 1], got {self.lr}")
        for name in ("grad_clip", "weight_decay"):
            if not (getattr(self, name) >= 0 and math.isfinite(getattr(self, name))):
                problems.append(f"{name} must be ≥ 0, got {getattr(self, name)}")
        if not 0.0 <= self.context_jitter <= 1.0:
            problems.append(f"context_jitter must lie in [0, 1], got {self.context_jitter}")
        elif self.context_jitter > 0 and self.sampling.counts is not None:
            problems.append(f"context_jitter ({self.context_jitter:g}) and sampling.counts {self.sampling.counts} both "
                            "draw each step's context count; give one of them")
        if int(self.patience) < 0 or int(self.lr_plateau) < 0:
            problems.append(f"patience and lr_plateau must be ≥ 0, got {self.patience} and {self.lr_plateau}")
        if int(self.render_every) < 0 or not 8 <= int(self.render_resolution) <= 1024:
            problems.append(f"render_every must be ≥ 0 and render_resolution in 8 … 1024, got {self.render_every} and "
                            f"{self.render_resolution}")
        if self.validate_through not in VALIDATION_CONTEXTS:
            problems.append(f"validate_through must be one of {VALIDATION_CONTEXTS}, got {self.validate_through!r}")
        if self.select not in SELECTION_RULES:
            problems.append(f"select must be one of {SELECTION_RULES}, got {self.select!r}")
        elif self.select == "psnr" and not self.render_every:
            problems.append("select 'psnr' needs render_every > 0 (the validation renders it selects by)")
        elif self.select == "psnr" and 0 < self.patience < self.render_every:
            problems.append(f"patience ({self.patience}) must be ≥ render_every ({self.render_every}) with select 'psnr'")
        if self.device not in ("cpu", "cuda", "auto"):
            problems.append(f"device must be 'cpu', 'cuda' or 'auto', got {self.device!r}")
        if not problems:  # the sizes are valid: what a step of them holds
            problems += self._step_memory_problems()
        if problems:
            raise ValueError("invalid training config: " + "; ".join(problems))
        train, val, test = self.split  # three, checked above
        self.split = (train, val, test)
        self.holdout = (self.holdout,) if isinstance(self.holdout, str) else tuple(self.holdout)

    def step_bytes(self) -> tuple[int, int, int, int]:
        """What a training step holds, computed from the config (nothing allocated): the bytes of activations per
        context sample and per query sample of a material, the fixed bytes per material (L_fre's NBRDF at the SHT
        nodes of every slice, when ``loss.eta`` > 0), and the bytes of the model's state (weights, gradients and
        Adam's two moments, float32).

        A layer's output and its ReLU's are kept for the backward pass: 2 float32 per hidden unit and sample (the
        backward pass's gradients live a layer at a time). An upper bound: the encoder's step at the defaults and
        30,000 context samples holds 0.49 GB, this says 0.78."""
        model = self.model
        encoder = sum(2 * sum((*e.hidden, *e.pooled)) + e.latent + SAMPLE_SIZE + _score_floats(e)
                      for e in model.encoders)
        nbrdf = 2 * sum(model.nbrdf.hidden) + N_INPUTS + N_OUTPUTS
        frequency = self.loss.frequency
        nodes = len(frequency.slices) * (frequency.nlat + 1) // 2 * (frequency.nlon // 2) if self.loss.eta > 0 else 0
        return 4 * encoder, 4 * nbrdf, 4 * nbrdf * nodes, 4 * 4 * model.n_parameters

    def _step_memory_problems(self) -> list[str]:
        """The largest sizes a step of this config may have within :data:`MAX_STEP_BYTES`, named, when it has more."""
        context, query, fixed, state = self.step_bytes()
        batch, n_query = int(self.batch_materials), int(self.query_samples)
        n_context = self.sampling.most_context(int(self.context_samples))
        total = state + batch * (n_context * context + n_query * query + fixed)
        if total <= MAX_STEP_BYTES:
            return []
        room = MAX_STEP_BYTES - state  # what the samples of a batch may take
        limits = {"context_samples" if self.sampling.counts is None else "sampling.counts' high":
                  (room // batch - n_query * query - fixed) // context,
                  "query_samples": (room // batch - n_context * context - fixed) // query,
                  "batch_materials": room // (n_context * context + n_query * query + fixed)}
        allowed = [f"{name} in 1 … {limit:,}" for name, limit in limits.items() if limit >= 1]
        return [f"a training step would hold {total / 2**30:.1f} GiB (every sample's activations for the backward "
                f"pass: {context:,} bytes per context sample, {query:,} per query sample"
                + (f", {fixed / 2**20:,.0f} MiB per material for L_fre's {self.loss.frequency.lmax}-degree nodes"
                   if fixed else "") + f"; {state / 2**20:,.0f} MiB of weights and optimiser state), more than "
                f"MAX_STEP_BYTES = {MAX_STEP_BYTES / 2**30:g} GiB: at the other settings, "
                + (" or ".join(allowed) if allowed else "no batch fits; choose a smaller model or L_fre lmax")]

    @property
    def cache_folder(self) -> Path:
        """Where the true SH coefficients are cached."""
        return Path(self.cache_dir or os.environ.get("FRENBRDF_CACHE") or Path.home() / ".cache" / "frenbrdf")


def config_for(method: str, *, training: str | None = None, augmentation: str | None = None,
               frequency: str | None = None, sampling: str | dict | SamplingConfig | None = None,
               **overrides) -> TrainConfig:
    """The preset of a method (:data:`frenbrdf.presets.METHODS`), optionally with a training length
    (``"demo"``, ``"sweep"``), an augmentation (:data:`frenbrdf.presets.AUGMENTATION`; by default
    :class:`AugmentConfig`'s, the ``"augmented"`` preset), an L_fre variant
    (:data:`frenbrdf.presets.FREQUENCY_VARIANTS`, ``"paper"`` by default) and a sampling
    (:data:`frenbrdf.presets.SAMPLING` by name, ``"paper"`` by default, or :class:`SamplingConfig` values as a dict
    or a config), with top-level fields overridden."""
    check_method(method)
    layers = [METHODS[method]]
    if training is not None:
        layers.append(training_overrides(training))
    if augmentation is not None:
        layers.append({"augment": augmentation_overrides(augmentation)})
    if isinstance(sampling, str):
        layers.append({"sampling": sampling_overrides(sampling)})
    elif sampling is not None:  # values: a config section like any other
        overrides["sampling"] = sampling
    if frequency is not None:
        layers.append({"loss": {"frequency": frequency_overrides(frequency)}})
    layers.append({key: to_dict(value) if dataclasses.is_dataclass(value) else value
                   for key, value in overrides.items()})
    settings = to_dict(TrainConfig(method=method))
    for layer in layers:
        settings = merge(settings, layer, TrainConfig)
    return from_dict(TrainConfig, settings, f"the {method} preset")


def load_config(path: str | os.PathLike, **overrides) -> TrainConfig:
    """A JSON config file (any subset of :class:`TrainConfig`'s keys) over its method's preset."""
    data = read_json(path, "training config", max_bytes=MAX_CONFIG_BYTES)
    data.update({key: value for key, value in overrides.items() if value is not None})
    return config_from_dict(data, str(path))


def config_from_dict(data: dict, where: str) -> TrainConfig:
    """A config's JSON object (any subset of :class:`TrainConfig`'s keys) over its method's preset, checked;
    ``where`` (a file, a row of one) starts every message."""
    if not isinstance(data.get("method", "frenbrdf"), str):
        raise ValueError(f"{where}: method must be a string, got {data['method']!r}")
    try:
        base = to_dict(config_for(data.get("method", "frenbrdf")))
        return from_dict(TrainConfig, merge(base, data, TrainConfig), where)
    except ValueError as error:  # the dataclasses' own checks do not know the file
        if where in str(error):
            raise
        raise ValueError(f"{where}: {error}") from None
