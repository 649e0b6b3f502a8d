"""The set encoder: DeepSets over (mapped RGB, H, D) samples, mean pooled into a latent."""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

#: One sample: mapped RGB (3) and the NBRDF coordinates H, D (6).
SAMPLE_SIZE = 9
#: The widest layer (hidden or latent) and the most hidden layers of the encoder and the decoder's heads.
MAX_WIDTH, MAX_LAYERS = 4096, 16


def mlp(sizes: list[int], dropout: float = 0.0) -> nn.Sequential:
    """Linear layers with ReLU between them (none after the last), each ReLU followed by dropout
    when ``dropout > 0`` (without it the layers, and so the state-dict keys, are the same as ever)."""
    layers: list[nn.Module] = []
    for fan_in, fan_out in zip(sizes[:-1], sizes[1:]):
        layers += [nn.Linear(fan_in, fan_out), nn.ReLU()] + ([nn.Dropout(dropout)] if dropout > 0 else [])
    return nn.Sequential(*layers[:-2 if dropout > 0 else -1])


@dataclass
class EncoderConfig:
    """Set encoder: per-sample MLP, then the mean over the samples."""

    hidden: tuple[int, ...] = (128, 128, 128)
    """Hidden widths of the per-sample MLP."""
    latent: int = 40
    """Size of the latent z."""
    dropout: float = 0.0
    """Dropout probability after each hidden layer of the per-sample MLP while training (0: none)."""

    def __post_init__(self):
        self.hidden = tuple(int(h) for h in self.hidden)
        if min(self.hidden, default=1) < 1 or self.latent < 1 or max((*self.hidden, self.latent)) > MAX_WIDTH \
                or len(self.hidden) > MAX_LAYERS:
            raise ValueError(f"encoder sizes must lie in 1 … {MAX_WIDTH} (at most {MAX_LAYERS} hidden layers), got "
                             f"hidden={self.hidden}, latent={self.latent}")
        if not 0.0 <= self.dropout < 1.0:
            raise ValueError(f"encoder dropout must lie in [0, 1), got {self.dropout}")


class SetEncoder(nn.Module):
    """``(B, N, 9)`` samples → ``(B, latent)``; any N ≥ 1, order-invariant."""

    def __init__(self, config: EncoderConfig):
        super().__init__()
        self.per_sample = mlp([SAMPLE_SIZE, *config.hidden, config.latent], config.dropout)

    def forward(self, samples: torch.Tensor) -> torch.Tensor:
        return self.per_sample(samples).mean(dim=-2)
