"""The set-encoder/hypernetwork autoencoder and the public :class:`Model`."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from torch import nn

from .. import checkpoints
from ..configs import from_dict
from .encoder import EncoderConfig, SetEncoder
from .hypernetwork import DecoderConfig, HyperNetwork
from .mapping import LogRelativeMapping, MappingConfig
from .nbrdf import NBRDF, NBRDFConfig, mapped_samples

#: :meth:`Model.encode` passes larger sample sets through the encoder in chunks of this size.
ENCODE_CHUNK = 16384


@dataclass
class ModelConfig:
    """Everything that fixes the shape of a model."""

    nbrdf: NBRDFConfig = field(default_factory=NBRDFConfig)
    encoder: EncoderConfig = field(default_factory=EncoderConfig)
    decoder: DecoderConfig = field(default_factory=DecoderConfig)
    mapping: MappingConfig = field(default_factory=MappingConfig)

    @classmethod
    def from_checkpoint(cls, checkpoint: dict) -> ModelConfig:
        """The model config saved in a checkpoint (inside its training config)."""
        return from_dict(cls, json.loads(checkpoint["config"])["model"], "checkpoint model config")


class AutoEncoder(nn.Module):
    """Samples ``(B, N, 9)`` → latents ``(B, latent)`` → NBRDF parameters (see :mod:`.nbrdf`)."""

    def __init__(self, config: ModelConfig):
        super().__init__()
        self.encoder = SetEncoder(config.encoder)
        self.decoder = HyperNetwork(config.encoder.latent, config.nbrdf.shapes(), config.decoder)

    def forward(self, samples: torch.Tensor) -> tuple[torch.Tensor, list[torch.Tensor]]:
        z = self.encoder(samples)
        return z, self.decoder(z)


class Model:
    """A trained FreNBRDF (or baseline) model: encode samples, decode latents, edit.

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
        #: The training config's loss settings (a dict of :class:`frenbrdf.losses.LossConfig` keys): the
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
        return cls.from_checkpoint(checkpoint, checkpoints.load_mapping(path, checkpoint))

    @classmethod
    def from_checkpoint(cls, checkpoint: dict, mapping_state: dict) -> Model:
        """A model from a loaded checkpoint (weights, ``config``, ``method``) and its mapping's state."""
        config = ModelConfig.from_checkpoint(checkpoint)
        network = AutoEncoder(config)
        network.load_state_dict({name: value.float() for name, value in checkpoint["model"].items()})
        loss = json.loads(checkpoint["config"]).get("loss", {})
        return cls(network, LogRelativeMapping.from_state(mapping_state), config, checkpoint["method"], loss)

    @classmethod
    def pretrained(cls, folder: str | os.PathLike | None = None) -> Model:
        """The model shipped inside the package (``frenbrdf/pretrained/``; docs/pretrained.md).

        ``folder``: a folder written by :func:`frenbrdf.pretrained.pack_pretrained` instead.

        Raises
        ------
        FileNotFoundError
            The package (or ``folder``) holds no packed model.
        ValueError
            A packed file is damaged or of another format (the message names it).
        """
        from ..pretrained import load_packed

        checkpoint, mapping_state, card = load_packed(folder)
        model = cls.from_checkpoint(checkpoint, mapping_state)
        model.card = card
        return model

    @torch.no_grad()
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
            ``(latent,)``.
        """
        mapped, coords, _ = mapped_samples(self.mapping, values, directions)
        samples = torch.from_numpy(np.concatenate([mapped, coords], axis=-1).astype(np.float32))
        if len(samples) <= ENCODE_CHUNK:
            return self.network.encoder(samples[None])[0].numpy().astype(np.float64)
        # The encoder is a per-sample MLP and a mean: a large set (all 1.1 million bins of a
        # table) goes through in chunks, which bounds memory and runs several times faster.
        total = sum(len(chunk) * self.network.encoder(chunk[None])[0].double() for chunk in samples.split(ENCODE_CHUNK))
        return (total / len(samples)).numpy()

    @torch.no_grad()
    def decode(self, z) -> NBRDF:
        """Latent(s) ``(latent,)`` or ``(B, latent)`` → :class:`NBRDF` (index it for one of B)."""
        z = np.asarray(z, dtype=np.float32)
        latent = self.config.encoder.latent
        if z.shape[-1:] != (latent,) or z.ndim > 2 or not np.all(np.isfinite(z)):
            raise ValueError(f"z must be finite with shape ({latent},) or (B, {latent}), got {z.shape}")
        return NBRDF(self.network.decoder(torch.from_numpy(z.reshape(-1, latent))), self.mapping)

    def reconstruct(self, values, directions, *, refine="full"):
        """Encodes samples, then refines the result on them (:func:`frenbrdf.reconstruct.reconstruct`).

        ``refine``: ``"none"``, ``"latent"``, ``"full"`` or a :class:`frenbrdf.reconstruct.RefineConfig`.
        Returns a :class:`frenbrdf.reconstruct.Reconstruction` (``.z``, ``.nbrdf``, ``.timings``, ``.losses``).
        """
        from ..reconstruct import reconstruct

        return reconstruct(self, values, directions, refine=refine)


def interpolate(z_a, z_b, t, *, extrapolate: bool = False) -> np.ndarray:
    """Linear interpolation of latents, ``(1 − t) z_a + t z_b`` (material editing).

    ``t`` is a number or an array (a leading axis is added). Values outside [0, 1]
    extrapolate beyond the two materials, which decodes to materials nobody measured:
    they raise ``ValueError`` unless ``extrapolate=True``.
    """
    z_a, z_b = np.asarray(z_a, dtype=np.float64), np.asarray(z_b, dtype=np.float64)
    if z_a.shape != z_b.shape:
        raise ValueError(f"latents must have the same shape, got {z_a.shape} and {z_b.shape}")
    t = np.asarray(t, dtype=np.float64)
    if not np.all(np.isfinite(t)):
        raise ValueError("t must be finite")
    if not extrapolate and (t.min() < 0 or t.max() > 1):
        raise ValueError(f"t must lie in [0, 1], got {t.min()} … {t.max()}; pass extrapolate=True to go beyond")
    t = t.reshape(t.shape + (1,) * z_a.ndim)
    return (1 - t) * z_a + t * z_b
