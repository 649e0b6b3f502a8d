"""The one registry of presets: what each method sets, and the standard training lengths.

A preset is a nested dict of :class:`~frenbrdf.training.TrainConfig` keys laid over the
defaults (:func:`frenbrdf.training.config_for` applies them). Methods (docs/method.md):

- ``frenbrdf``: L1 reconstruction + η · L_fre (the defaults);
- ``nbrdf``: the same autoencoder with η = 0;
- ``hyperbrdf``: HyperBRDF's settings, as its own main.py and data_processing.py run:
  MSE on cos-weighted values in its mapping ln(1 + (f + ε)/(f_med + ε)), a 6→60×4→3
  NBRDF, λ1 = λ2 = 0.1 with the weight penalty the mean over all weights together,
  learning rate 5e-5, gradient norm clipped at 1, its hypernetwork's last layers started small and
  the per-bin median as reference.

Training lengths are top-level overrides for a whole comparison, the same for every
method, so that every method takes the same number of optimisation steps: the paper's
protocol uses the defaults; ``demo`` fits ``frenbrdf demo`` in minutes on 2 cores;
``sweep`` is half the demo, for the many runs of sweeps and ``frenbrdf select``.

Augmentations (:data:`AUGMENTATION`) say what data a comparison trained on, the same for every
method: the tables only (``paper``) or with mixes, gains and procedural materials. Samplings
(:data:`SAMPLING`) say how the encoder's samples of a material were drawn: random valid MERL bins
(``paper``) or the patterns of real instruments (``instruments``).
"""

from __future__ import annotations

METHODS: dict[str, dict] = {
    "frenbrdf": {},
    "nbrdf": {"loss": {"eta": 0.0}},
    "hyperbrdf": {
        "loss": {"kind": "mse", "lambda_weights": 0.1, "weight_penalty": "all", "lambda_latent": 0.1, "eta": 0.0},
        # Its hypernetwork starts its heads' last layers small (Kaiming / 100 in its code; ours 0.1)
        # and maps by the per-bin median, as its data_processing does.
        "model": {"nbrdf": {"hidden": [60, 60, 60, 60]}, "decoder": {"last_layer_scale": 0.1},
                  "mapping": {"form": "one_plus_ratio", "reference": "per_bin"}},
        "lr": 5e-5,
        "grad_clip": 1.0,
    },
}
"""Method → its overrides of the defaults."""

TRAINING: dict[str, dict] = {
    "demo": {"epochs": 100, "batch_materials": 8, "context_samples": 2000, "query_samples": 2000},
    "sweep": {"epochs": 50, "batch_materials": 8, "context_samples": 2000, "query_samples": 2000},
}
"""Training length → top-level overrides, the same for every method."""


AUGMENTATION: dict[str, dict] = {
    "paper": {"mix": 0.0, "gain": 0.0, "procedural": 0.0},
    # The default (AugmentConfig's): chosen by measurement, research/colour.md. Procedural materials
    # made steps 1.7x slower and did not help at the demo's length, so they are off here.
    "augmented": {"mix": 0.25, "gain": 0.5, "procedural": 0.0, "gain_range": [0.5, 2.0]},
    "procedural": {"mix": 0.25, "gain": 0.25, "procedural": 0.25, "gain_range": [0.5, 2.0]},
}
"""Augmentation → its :class:`~frenbrdf.training.config.AugmentConfig` values, the same for every
method: ``paper`` trains on the tables only (the paper's protocol), ``augmented`` (the default)
adds mixes and colour gains, ``procedural`` also analytic materials drawn afresh (docs/data.md)."""


#: Every sampling pattern of :data:`frenbrdf.io.patterns.PATTERNS` (named here, so that this registry imports nothing).
ALL_PATTERNS = ("merl-bins", "uniform", "cosine", "in-plane", "gonioreflectometer", "image-based", "flat-sample",
                "specular", "back-scatter", "peaks")

SAMPLING: dict[str, dict] = {
    "paper": {"patterns": {"merl-bins": 1.0}, "counts": None},
    "instruments": {"patterns": dict.fromkeys(ALL_PATTERNS, 1.0), "counts": [300, 4000]},
    # Random bins half the time, each other pattern one time in eighteen: research/results/sampling-patterns.
    "mixed": {"patterns": {**dict.fromkeys(ALL_PATTERNS, 1.0), "merl-bins": 9.0}, "counts": [300, 4000]},
}
"""Sampling → its :class:`~frenbrdf.training.config.SamplingConfig` values, the same for every method: how each
training step draws the samples the encoder reads (docs/data.md, "Sampling patterns"). ``paper`` (the default) draws
random valid MERL bins, ``context_samples`` of them, as the paper does; ``instruments`` gives each material of a step
one of the ten patterns of :mod:`frenbrdf.io.patterns` with equal chances, and each step 300 … 4000 samples,
log-uniform (what devices give, from a gonioreflectometer's few hundred readings to a capture of thousands);
``mixed`` draws random bins for half the materials and the nine other patterns for the rest, with the same
counts. The sampling-patterns study (research/results/sampling-patterns) chose ``mixed``: it reads the devices'
patterns about 6 dB better than ``paper`` and random bins as well, where ``instruments`` loses 4 dB on random
bins."""


FREQUENCY_VARIANTS: dict[str, dict] = {
    "paper": {"fit": "sphere", "values": "mapped", "degree_power": 0.0, "slices": [0, 24, 48, 72]},
    "no-floor": {"fit": "measured", "values": "mapped", "degree_power": 0.0, "slices": [0, 24, 48, 72]},
    "tone": {"fit": "measured", "values": "log1p", "degree_power": 0.0, "slices": [0, 24, 48, 72]},
    "highlights": {"fit": "measured", "values": "log1p", "degree_power": 0.0, "slices": [1, 4, 10, 21]},
}
"""L_fre variant → its :class:`~frenbrdf.models.losses.FrequencyLossConfig` values (research/frequency.md,
"Variants"). ``paper`` is the paper's reading (the default). Each next one removes one more measured
reason why L_fre is inert: ``no-floor`` fits the coefficients to the measured nodes only (no floor
below the horizon); ``tone`` also takes the spectrum of ln(1 + f) instead of the log-relative
values; ``highlights`` also moves the slices to where the energy is: θ_h bins 1, 4, 10, 21 (0.01°, 0.2°,
1.1°, 4.9°), the 12.5, 37.5, 62.5 and 87.5 % quantiles over θ_h of the mean energy of ln(1 + f) of 20
MERL-derived materials (the paper's slices reach 57.6°, where 1 % of it lies)."""


def frequency_overrides(name: str) -> dict:
    """The ``loss.frequency`` values of an L_fre variant, its name recorded in them."""
    if name not in FREQUENCY_VARIANTS:
        raise ValueError(f"frequency variant must be one of {sorted(FREQUENCY_VARIANTS)}, got {name!r}")
    return {**FREQUENCY_VARIANTS[name], "variant": name}


SELECTION_RULES: tuple[str, ...] = ("loss", "psnr")
"""What can pick a run's best checkpoint (``TrainConfig.select``): the validation loss, or the validation
render PSNR."""


def augmentation_overrides(name: str) -> dict:
    """The ``augment`` values of an augmentation preset, its name recorded in them."""
    if name not in AUGMENTATION:
        raise ValueError(f"augmentation must be one of {sorted(AUGMENTATION)}, got {name!r}")
    return {**AUGMENTATION[name], "preset": name}


def sampling_overrides(name: str) -> dict:
    """The ``sampling`` values of a sampling preset, its name recorded in them."""
    if name not in SAMPLING:
        raise ValueError(f"sampling must be one of {sorted(SAMPLING)}, got {name!r}")
    entry = SAMPLING[name]
    return {"patterns": dict(entry["patterns"]), "counts": entry["counts"], "preset": name}


def method_names() -> tuple[str, ...]:
    """The methods, in the order tables list them."""
    return tuple(METHODS)


def check_method(method: str) -> str:
    """``method`` if it names a preset, else ValueError naming the valid ones."""
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"method must be one of {method_names()}, got {method!r}")
    return method


def training_overrides(name: str) -> dict:
    """The top-level overrides of a training length (``demo``, ``sweep``)."""
    if name not in TRAINING:
        raise ValueError(f"training preset must be one of {sorted(TRAINING)}, got {name!r}")
    return dict(TRAINING[name])
