"""The set-encoder/hypernetwork autoencoder and the public :class:`Model`."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from torch import nn

from ..configs import from_dict
from ..io import checkpoints
from ..io.jsonfile import parse_json
from .editing import EditedMaterial, edit
from .editing import interpolate as interpolate  # its home until editing had one; imported from here by many
from .encoder import ENCODER_CHOICES, EncoderConfig, EncoderMean, SetEncoder
from .hypernetwork import DecoderConfig, HyperNetwork
from .losses import LossConfig, samples_loss
from .mapping import LogRelativeMapping, MappingConfig
from .nbrdf import NBRDF, NBRDFConfig, mapped_samples
from .second_look import SecondLookConfig, build_second_look

#: :meth:`Model.encode` passes larger sample sets through the encoder in chunks of this size.
ENCODE_CHUNK = 16384
#: The most parameters a model may have (1 GiB of float32): a config read from a file is checked against it before
#: anything is allocated. The default model has about 1.6 million.
MAX_PARAMETERS = 1 << 28


@dataclass
class ModelConfig:
    """Everything that fixes the shape of a model."""

    nbrdf: NBRDFConfig = field(default_factory=NBRDFConfig)
    encoder: EncoderConfig = field(default_factory=EncoderConfig)
    decoder: DecoderConfig = field(default_factory=DecoderConfig)
    mapping: MappingConfig = field(default_factory=MappingConfig)
    extra_encoders: tuple[EncoderConfig, ...] = ()
    """More set encoders of the same latent space (:class:`~.encoder.EncoderMean`; ``release/pack_encoder_mean.py``
    builds one from encoders trained for one decoder); :attr:`encoder_choice` says how their latents give z."""
    encoder_choice: str = "mean"
    """With :attr:`extra_encoders`, how :meth:`Model.encode` takes z from the encoders' latents: ``"mean"``, their
    mean; ``"best-fit"``, the one latent whose decoding fits the given samples best (the smallest reconstruction
    loss on them: the objective ``latent`` refinement lowers next). Encoders trained on different sampling patterns
    each read best what they trained on, and the samples say which that is (research/results/version-5)."""
    second_look: SecondLookConfig | None = None
    """A second look after the encoders (:mod:`.second_look`): :meth:`Model.encode` corrects their z from the samples'
    errors under it. None (every model before it): z is the encoders'. Training (:mod:`frenbrdf.training`) reads the
    encoders only; the second look is trained for a finished model by ``research/studies/second_look.py``."""

    def __post_init__(self):
        self.extra_encoders = tuple(self.extra_encoders)
        if self.encoder_choice not in ENCODER_CHOICES:
            raise ValueError(f"encoder_choice must be one of {ENCODER_CHOICES}, got {self.encoder_choice!r}")
        if any(extra.latent != self.encoder.latent for extra in self.extra_encoders):
            raise ValueError(f"extra encoders must have the latent size of the encoder ({self.encoder.latent}), got "
                             f"{[extra.latent for extra in self.extra_encoders]}")
        if self.n_parameters > MAX_PARAMETERS:
            raise ValueError(f"this model config has {self.n_parameters:,} parameters, more than the {MAX_PARAMETERS:,} "
                             f"a model may have (encoder {self.encoder.hidden} → {self.encoder.latent}, decoder heads "
                             f"{self.decoder.hidden} for an NBRDF of {self.nbrdf.hidden})")

    @property
    def n_parameters(self) -> int:
        """How many parameters the network of this config has (computed, nothing allocated)."""
        def mlp(sizes) -> int:
            return sum(a * b + b for a, b in zip(sizes[:-1], sizes[1:], strict=True))

        from .encoder import SAMPLE_SIZE, SCORE_HIDDEN

        latent = self.encoder.latent

        def encoder_size(encoder: EncoderConfig) -> int:
            scores = mlp([SAMPLE_SIZE, SCORE_HIDDEN, encoder.attention_heads]) if encoder.pooling == "attention" else 0
            return scores + (mlp([SAMPLE_SIZE, *encoder.hidden]) + mlp([encoder.hidden[-1], *encoder.pooled, latent])
                             if encoder.pooled else mlp([SAMPLE_SIZE, *encoder.hidden, latent]))

        look = self.second_look.n_parameters(latent) if self.second_look is not None else 0
        return look + sum(map(encoder_size, self.encoders)) + sum(
            mlp([latent, *self.decoder.hidden, math.prod(shape)]) for shape in self.nbrdf.shapes())

    @property
    def encoders(self) -> tuple[EncoderConfig, ...]:
        """Every encoder's config, the first one's first."""
        return (self.encoder, *self.extra_encoders)

    @classmethod
    def from_checkpoint(cls, checkpoint: dict) -> ModelConfig:
        """The model config saved in a checkpoint (inside its training config)."""
        training = parse_json(checkpoint["config"], "checkpoint config", "training config")
        return from_dict(cls, training.get("model"), "checkpoint model config")


class AutoEncoder(nn.Module):
    """Samples ``(B, N, 9)`` → latents ``(B, latent)`` → NBRDF parameters (see :mod:`frenbrdf.models.nbrdf`)."""

    def __init__(self, config: ModelConfig):
        super().__init__()
        self.encoder = SetEncoder(config.encoder) if not config.extra_encoders else EncoderMean(config.encoders)
        self.decoder = HyperNetwork(config.encoder.latent, config.nbrdf.shapes(), config.decoder)
        self.second_look = (build_second_look(config.encoder.latent, config.second_look) if config.second_look is not None
                            else None)

    def forward(self, samples: torch.Tensor) -> tuple[torch.Tensor, list[torch.Tensor]]:
        """The encoders' z (the first look: training reads no second look) and its decoding."""
        z = self.encoder(samples)
        return z, self.decoder(z)


@dataclass
class Encoding:
    """What :meth:`Model.encoding` found: z and every encoder's latent, and for a best-fit choice what chose it."""

    z: np.ndarray
    """The latent ``(latent,)``: the chosen encoder's, or the mean of all of them."""
    latents: np.ndarray
    """Each encoder's latent, ``(encoders, latent)``, in the model's order."""
    poolings: list[str]
    """Each encoder's pooling (``EncoderConfig.pooling``)."""
    losses: np.ndarray | None = None
    """With ``encoder_choice="best-fit"``: each latent's decoding's reconstruction loss on the samples."""
    chosen: int | None = None
    """With ``encoder_choice="best-fit"``: the index of the encoder whose latent is z; None: z is their mean."""
    first_look: np.ndarray | None = None
    """With a second look (:mod:`.second_look`): the encoders' z, before it corrected it; None without one."""
    looks: int = 0
    """How many second looks corrected z: ``SecondLookConfig.steps``, or with its ``choice="best-fit"`` those that
    led to the z chosen (0 also without a second look)."""
    look_losses: np.ndarray | None = None
    """With a second look's ``choice="best-fit"``: the samples' loss under the encoders' z and after each look."""

    def summary(self) -> dict:
        """JSON-ready: how z was chosen (the latents themselves are left out)."""
        look: dict[str, object] = {} if self.first_look is None else {"second_look": True, "looks": self.looks}
        if self.look_losses is not None:
            look["look_losses"] = [float(loss) for loss in self.look_losses]
        if self.chosen is None or self.losses is None:  # set together
            return {"encoders": len(self.latents), "choice": "mean", **look}
        return {"encoders": len(self.latents), "choice": "best-fit", "chosen": self.chosen,
                "pooling": self.poolings[self.chosen], "losses": [float(loss) for loss in self.losses], **look}


class Model:
    """A trained FreNBRDF (or baseline) model: encode samples, decode latents, reconstruct, edit.

    Examples
    --------
    >>> model = frenbrdf.Model.load("runs/frenbrdf")                  # doctest: +SKIP
    >>> z = model.encode(values, (wi, wo))   # values (N, 3) reflectance; wi, wo (N, 3)
    >>> nbrdf = model.decode(z)                                          # doctest: +SKIP
    >>> nbrdf(wi, wo).shape                                              # doctest: +SKIP
    (N, 3)
    """

    def __init__(self, network: AutoEncoder, mapping: LogRelativeMapping, config: ModelConfig, method: str = "",
                 loss: dict | None = None):
        self.network = network.eval()
        self.mapping, self.config, self.method = mapping, config, method
        #: The training config's loss settings (a dict of :class:`frenbrdf.models.losses.LossConfig` keys): the
        #: objective :meth:`reconstruct` refines with. Empty: LossConfig's defaults.
        self.loss = dict(loss or {})
        #: The model card of a packaged model (:meth:`pretrained`); empty for run folders.
        self.card: dict = {}

    @classmethod
    def load(cls, path: str | os.PathLike) -> Model:
        """Loads a checkpoint file, or the best checkpoint of a run folder."""
        path = Path(path)
        if path.is_dir():
            path = path / "best.pt"
        checkpoint = checkpoints.load(path)
        return cls.from_checkpoint(checkpoint, checkpoints.load_mapping(path, checkpoint), source=str(path))

    @classmethod
    def from_checkpoint(cls, checkpoint: dict, mapping_state: dict, *, source: str = "checkpoint") -> Model:
        """A model from a loaded checkpoint (weights, ``config``, ``method``) and its mapping's state.

        Everything is checked before the network is built: the config (types, sizes), that the weights
        have the shapes the config gives them, and that they are finite. ``source`` names the file in errors.
        """
        try:
            training = parse_json(checkpoint["config"], "its training config", "training config", expect=None)
            if not isinstance(training, dict) or not isinstance(training.get("model"), dict):
                raise ValueError("its training config holds no model settings")
            config = from_dict(ModelConfig, training["model"], "its model config")
            method, weights = checkpoint["method"], checkpoint["model"]
            if not isinstance(weights, dict) or not all(isinstance(w, torch.Tensor) for w in weights.values()):
                raise ValueError("its weights are not a dict of tensors")
            with torch.device("meta"):  # the shapes the config gives the weights, nothing allocated
                expected = {name: tuple(p.shape) for name, p in AutoEncoder(config).state_dict().items()}
            given = {name: tuple(w.shape) for name, w in weights.items()}
            if given != expected:
                differ = sorted(set(given) ^ set(expected)) or [n for n in expected if given[n] != expected[n]]
                name = differ[0]
                raise ValueError(f"its weights do not match its model config: {name} is "
                                 f"{given.get(name, 'missing')}, the config gives {expected.get(name, 'no such tensor')}")
            bad = [name for name, w in weights.items() if not torch.all(torch.isfinite(w))]
            if bad:
                raise ValueError(f"its weights hold NaN or inf ({', '.join(bad[:3])}): the model is damaged")
            mapping = LogRelativeMapping.from_state(mapping_state)
        except (KeyError, TypeError) as error:
            raise ValueError(f"{source}: not a complete frenbrdf model (missing or wrong {error})") from None
        except ValueError as error:
            raise ValueError(f"{source}: {error}") from None
        network = AutoEncoder(config)
        network.load_state_dict({name: value.float() for name, value in weights.items()})
        return cls(network, mapping, config, method, training.get("loss", {}))

    @classmethod
    def pretrained(cls, folder: str | os.PathLike | None = None) -> Model:
        """The model shipped inside the package (``frenbrdf/models/pretrained/``; docs/pretrained.md).

        ``folder``: a folder written by :func:`frenbrdf.models.pretrained.pack_pretrained` instead.

        Raises
        ------
        FileNotFoundError
            The package (or ``folder``) holds no packed model.
        ValueError
            A packed file is damaged or of another format (the message names it).
        """
        from .pretrained import load_packed

        checkpoint, mapping_state, card = load_packed(folder)
        model = cls.from_checkpoint(checkpoint, mapping_state)
        model.card = card
        return model

    def encode(self, values, directions) -> np.ndarray:
        """Latent of one material from its samples.

        Parameters
        ----------
        values
            Reflectance ``(N, 3)`` (physical units, ≥ 0; leave missing samples out).
        directions
            ``(wi, wo)``, unit vectors ``(N, 3)`` each, above the surface.

        Returns
        -------
        numpy.ndarray
            ``(latent,)``: :meth:`encoding`'s ``z``.
        """
        return self.encoding(values, directions).z

    @torch.no_grad()
    def encoding(self, values, directions) -> Encoding:
        """:meth:`encode` with what it chose from: every encoder's latent and, with ``encoder_choice="best-fit"``,
        each decoding's loss on the samples and which encoder gave z; with a second look, the z it corrected
        (:class:`Encoding`)."""
        mapped, coords, cos_in = mapped_samples(self.mapping, values, directions)
        encoding = self._first_look(mapped, coords, cos_in)
        look, config = self.network.second_look, self.config.second_look
        if look is None or config is None:  # set together
            return encoding
        at, truth, cos = (torch.from_numpy(a.astype(np.float32))[None] for a in (coords, mapped, cos_in))
        zs = [torch.from_numpy(encoding.z.astype(np.float32))[None]]
        for _ in range(config.steps):
            zs.append(look(at, truth, cos, zs[-1], self.network.decoder))
        looks = config.steps
        if config.choice == "best-fit":  # scored as the encoders' best-fit choice scores
            encoding.look_losses = self._fit_losses(zs, at, truth, cos)
            looks = int(np.argmin(encoding.look_losses))
        encoding.first_look, encoding.z, encoding.looks = encoding.z, zs[looks][0].double().numpy(), looks
        return encoding

    def _fit_losses(self, latents: list[torch.Tensor], at: torch.Tensor, truth: torch.Tensor,
                    cos: torch.Tensor) -> np.ndarray:
        """Each latent ``(1, latent)``'s decoding scored on the prepared samples, as refinement scores it: what a
        best-fit choice (of encoders, or of looks) compares."""
        kind = self.loss.get("kind", LossConfig.kind)
        return np.array([samples_loss(self.network.decoder(z), at, truth, cos, kind) for z in latents])

    def _first_look(self, mapped: np.ndarray, coords: np.ndarray, cos_in: np.ndarray) -> Encoding:
        """The encoders' z from prepared samples: their mean, or the best-fitting one's."""
        samples = torch.from_numpy(np.concatenate([mapped, coords], axis=-1).astype(np.float32))
        encoder = self.network.encoder
        members = encoder.encoders() if isinstance(encoder, EncoderMean) else [encoder]
        latents = np.stack([member(samples[None])[0].numpy().astype(np.float64) if len(samples) <= ENCODE_CHUNK
                            else encode_in_chunks(member, samples) for member in members])
        poolings = [member.pooling for member in members]
        if self.config.encoder_choice == "mean" or len(latents) == 1:
            return Encoding(latents.mean(axis=0), latents, poolings)
        # best-fit: each latent's decoding scored on the samples, as refinement scores it
        at, truth, cos = (torch.from_numpy(a.astype(np.float32))[None] for a in (coords, mapped, cos_in))
        losses = self._fit_losses([torch.from_numpy(z.astype(np.float32))[None] for z in latents], at, truth, cos)
        chosen = int(np.argmin(losses))
        return Encoding(latents[chosen], latents, poolings, losses, chosen)

    @torch.no_grad()
    def decode(self, z) -> NBRDF:
        """Latent(s) ``(latent,)`` or ``(B, latent)`` → :class:`NBRDF` (index it for one of B)."""
        z = np.asarray(z, dtype=np.float32)
        latent = self.config.encoder.latent
        if z.shape[-1:] != (latent,) or z.ndim > 2:
            raise ValueError(f"z must have shape ({latent},) or (B, {latent}), got {z.shape}")
        if not np.all(np.isfinite(z)):
            raise ValueError("z must be finite, got NaN or inf")
        return NBRDF(self.network.decoder(torch.from_numpy(z.reshape(-1, latent))), self.mapping)

    def reconstruct(self, values, directions, *, refine="full"):
        """Encodes samples, then refines the result on them (:func:`frenbrdf.models.reconstruct.reconstruct`).

        ``refine``: ``"none"``, ``"latent"``, ``"full"`` or a :class:`frenbrdf.models.reconstruct.RefineConfig`.
        Returns a :class:`frenbrdf.models.reconstruct.Reconstruction` (``.z``, ``.nbrdf``, ``.timings``, ``.losses``).
        """
        from .reconstruct import reconstruct

        return reconstruct(self, values, directions, refine=refine)

    def edit(self, a, b, t) -> EditedMaterial:
        """The edit between two reconstructions of this model that keeps each (:func:`frenbrdf.models.editing.edit`).

        ``a``, ``b``: :class:`frenbrdf.models.reconstruct.Reconstruction` s (``refine="full"``: what refinement
        added beyond the decoding is carried along and faded out); ``t``: a position in [0, 1] or a 1-D array of
        them. Returns a :class:`frenbrdf.models.editing.EditedMaterial`, each material itself at t = 0 and 1. The
        plain latent interpolation stays ``model.decode(interpolate(a.z, b.z, t))``.
        """
        return edit(self, a, b, t)


def encode_in_chunks(encoder: SetEncoder, samples: torch.Tensor) -> np.ndarray:
    """The latent of a large sample set ``(N, 9)``: a set encoder is a per-sample MLP, a mean and ρ, so
    the set (all 1.1 million bins of a table) goes through in chunks, which bounds memory and runs several
    times faster. With density or attention pooling the weights are those of the whole set (computed once)."""
    weights = encoder.weights(samples[None])
    if weights is None:
        total = sum((len(chunk) * encoder.pooled_features(chunk[None])[0].double()
                     for chunk in samples.split(ENCODE_CHUNK)), torch.zeros((), dtype=torch.float64))
        mean = total / len(samples)  # float64: a mean of up to a million codes; ρ then runs in float32
    else:  # each chunk's weighted sum, with its share of the whole set's weights (they sum to 1)
        mean = sum((encoder.pooled_features(chunk[None], part[None])[0].double()
                    for chunk, part in zip(samples.split(ENCODE_CHUNK), weights[0].split(ENCODE_CHUNK), strict=True)),
                   torch.zeros((), dtype=torch.float64))
    if isinstance(encoder.after_pool, nn.Identity):
        return mean.numpy()
    return encoder.after_pool(mean.float()[None])[0].double().numpy()


def load_model(model: str | os.PathLike) -> Model:
    """``"pretrained"`` (the packaged model, :meth:`Model.pretrained`), a packed model's folder (``card.json``
    beside ``model.pt``), a run folder or a checkpoint file."""
    if str(model) == "pretrained":
        return Model.pretrained()
    path = Path(model)
    if not path.exists():
        raise FileNotFoundError(f"model {path} does not exist (give a training run folder, a checkpoint file, a "
                                "packed model's folder or 'pretrained')")
    if path.is_dir() and (path / "card.json").exists():  # a FIFO there is refused by the card's reader
        return Model.pretrained(path)
    return Model.load(path)
