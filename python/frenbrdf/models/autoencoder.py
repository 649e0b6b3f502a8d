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
from .nbrdf import NBRDF, NBRDFConfig, nbrdf_coordinates

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

    def __init__(self, network: AutoEncoder, mapping: LogRelativeMapping, config: ModelConfig, method: str = ""):
        self.network = network.eval()
        self.mapping, self.config, self.method = mapping, config, method

    @classmethod
    def load(cls, path: str | os.PathLike) -> Model:
        """Loads a checkpoint file, or the best checkpoint of a run folder."""
        path = Path(path)
        if path.is_dir():
            path = path / "best.pt"
        checkpoint = checkpoints.load(path)
        config = ModelConfig.from_checkpoint(checkpoint)
        network = AutoEncoder(config)
        network.load_state_dict(checkpoint["model"])
        mapping = LogRelativeMapping.from_state(checkpoints.load_mapping(path, checkpoint))
        return cls(network, mapping, config, checkpoint["method"])

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
        values = np.asarray(values, dtype=np.float64)
        wi, wo = (np.asarray(d, dtype=np.float64) for d in directions)
        if values.ndim != 2 or values.shape[1] != 3 or len(values) == 0:
            raise ValueError(f"values must have shape (N, 3) with N ≥ 1, got {values.shape}")
        if wi.shape != values.shape or wo.shape != values.shape:
            raise ValueError(f"wi and wo must have the shape of values {values.shape}, got {wi.shape} and {wo.shape}")
        if not np.all(np.isfinite(values)) or values.min() < 0:
            raise ValueError("values must be finite and ≥ 0 (leave missing samples out)")
        mapped = self.mapping.forward(values, self.mapping.reference_at(wi, wo))
        samples = torch.from_numpy(np.concatenate([mapped, nbrdf_coordinates(wi, wo)], axis=-1).astype(np.float32))
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
