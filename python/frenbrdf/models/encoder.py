"""The set encoder: DeepSets over (mapped RGB, H, D) samples, mean pooled into a latent.

DeepSets is z = ρ(mean φ(sample)). The paper's encoder (the default) has no ρ: z is the mean of
per-sample codes, a linear functional of the samples' distribution. ``EncoderConfig.pooled`` gives it
a ρ, an MLP after the mean, so that z can depend non-linearly on what the samples show together
(research/measurements.md measures what that does to the encoder's gap on real materials).
"""

from __future__ import annotations

from collections.abc import Sequence
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
    for fan_in, fan_out in zip(sizes[:-1], sizes[1:], strict=True):
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
    pooled: tuple[int, ...] = ()
    """Hidden widths of DeepSets' ρ, an MLP from the mean of the last hidden layer's features to the latent;
    () (the paper's encoder): no ρ, the per-sample MLP ends in the latent and z is the mean of its outputs."""

    def __post_init__(self):
        self.hidden = tuple(int(h) for h in self.hidden)
        self.pooled = tuple(int(h) for h in self.pooled)
        widths = (*self.hidden, *self.pooled, self.latent)
        if min(widths) < 1 or max(widths) > MAX_WIDTH or max(len(self.hidden), len(self.pooled)) > MAX_LAYERS:
            raise ValueError(f"encoder sizes must lie in 1 … {MAX_WIDTH} (at most {MAX_LAYERS} hidden layers each), got "
                             f"hidden={self.hidden}, pooled={self.pooled}, latent={self.latent}")
        if self.pooled and not self.hidden:
            raise ValueError("an encoder with a ρ (pooled) needs hidden layers: ρ reads the mean of the last one")
        if not 0.0 <= self.dropout < 1.0:
            raise ValueError(f"encoder dropout must lie in [0, 1), got {self.dropout}")


class SetEncoder(nn.Module):
    """``(B, N, 9)`` samples → ``(B, latent)``; any N ≥ 1, order-invariant."""

    def __init__(self, config: EncoderConfig):
        super().__init__()
        self.after_pool: nn.Module
        if config.pooled:  # φ ends in a ReLU; its mean goes through ρ
            self.per_sample = nn.Sequential(mlp([SAMPLE_SIZE, *config.hidden], config.dropout), nn.ReLU())
            self.after_pool = mlp([config.hidden[-1], *config.pooled, config.latent])
        else:  # the paper's encoder: the same state-dict keys as ever
            self.per_sample = mlp([SAMPLE_SIZE, *config.hidden, config.latent], config.dropout)
            self.after_pool = nn.Identity()

    def pooled_features(self, samples: torch.Tensor) -> torch.Tensor:
        """The mean over the samples of the per-sample features, ``(B, N, 9)`` → ``(B, F)``: what ρ reads."""
        return self.per_sample(samples).mean(dim=-2)

    def forward(self, samples: torch.Tensor) -> torch.Tensor:
        return self.after_pool(self.pooled_features(samples))


class EncoderMean(nn.Module):
    """Several set encoders of one latent space; z is the mean of their latents.

    Encoders trained for one decoder agree on the materials they trained near, and give an unseen
    saturated one different hues, depending on their seed (research/results/encoder-refit); their mean
    depends on the seed less."""

    def __init__(self, configs: Sequence[EncoderConfig]):
        super().__init__()
        self.members = nn.ModuleList(SetEncoder(config) for config in configs)

    def encoders(self) -> list[SetEncoder]:
        """The members, typed."""
        return [member for member in self.members if isinstance(member, SetEncoder)]

    def forward(self, samples: torch.Tensor) -> torch.Tensor:
        return torch.stack([member(samples) for member in self.members]).mean(dim=0)
