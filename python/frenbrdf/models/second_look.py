"""The encoder's second look: one learned step from what its first guess got wrong.

An encoder reads the samples once and guesses z₁. `latent` refinement then reads the samples' errors under the
guess and steps z by their gradient, 600 times. The second look takes one learned step of that kind: z₁ is decoded at
the samples, a set network reads each sample with its prediction ŷ, its error y − ŷ, cos θ_i and z₁, pools the
mean, and from it, z₁ and the samples' loss gradient at z₁ (its direction and log length) gives Δz; z = z₁ + Δz.
Its last layer starts at zero, so an untrained second look is the first. It is trained for a frozen decoder and
frozen encoders (research/results/second-look), and costs one decoding and one backward pass through it.
:attr:`SecondLookConfig.steps` takes it again from its own answer, z₃ = look(z₂), … (research/results/repeated-look),
and :attr:`SecondLookConfig.choice` ``"best-fit"`` keeps whichever z fits the samples best. With
:attr:`SecondLookConfig.members` several looks, trained apart for the same encoders, answer each step and z is their
mean (:class:`LookMean`, research/results/look-ensemble); they share the step's decoding and backward pass.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import torch
from torch import nn

from .encoder import MAX_LAYERS, MAX_WIDTH, mlp
from .nbrdf import nbrdf_forward

#: What the second look reads of each sample besides z₁: y (3), the coordinates (6), ŷ (3), y − ŷ (3), cos θ_i (1).
SAMPLE_FEATURES = 16
#: The most looks an encoding may take (each costs a decoding and a backward pass through it).
MAX_STEPS = 16
#: The most looks whose answers one step may average (:attr:`SecondLookConfig.members`).
MAX_MEMBERS = 8
#: How z is taken from the looks (:attr:`SecondLookConfig.choice`).
LOOK_CHOICES = ("last", "best-fit")


@dataclass
class SecondLookConfig:
    """The second look's sizes."""

    hidden: tuple[int, ...] = (128, 128, 128)
    """Hidden widths of the per-sample network."""
    after: tuple[int, ...] = (256, 256)
    """Hidden widths of the network from the pooled features, z₁ and the gradient to Δz."""
    steps: int = 1
    """How many looks :meth:`Model.encode <frenbrdf.Model.encode>` takes, each from the z the one before gave
    (research/results/repeated-look)."""
    choice: str = "last"
    """``"last"``: z is the last look's; ``"best-fit"``: of the encoders' z and every look's, the one whose decoding
    fits the samples best (research/results/look-choice)."""
    members: int = 1
    """How many looks, trained apart for the same encoders, answer at each step; z is the mean of their answers
    (research/results/look-ensemble)."""

    def __post_init__(self):
        self.hidden, self.after = tuple(int(h) for h in self.hidden), tuple(int(h) for h in self.after)
        if isinstance(self.steps, bool) or not isinstance(self.steps, int) or not 1 <= self.steps <= MAX_STEPS:
            raise ValueError(f"second look steps must be a whole number in 1 … {MAX_STEPS}, got {self.steps!r}")
        if isinstance(self.members, bool) or not isinstance(self.members, int) or not 1 <= self.members <= MAX_MEMBERS:
            raise ValueError(f"second look members must be a whole number in 1 … {MAX_MEMBERS}, got {self.members!r}")
        if self.choice not in LOOK_CHOICES:
            raise ValueError(f"second look choice must be one of {LOOK_CHOICES}, got {self.choice!r}")
        widths = (*self.hidden, *self.after)
        if not self.hidden or min(widths) < 1 or max(widths) > MAX_WIDTH or max(len(self.hidden),
                                                                               len(self.after)) > MAX_LAYERS:
            raise ValueError(f"second look sizes must lie in 1 … {MAX_WIDTH}, at most {MAX_LAYERS} layers each and "
                             f"at least one hidden layer, got hidden={self.hidden}, after={self.after}")

    def n_parameters(self, latent: int) -> int:
        """How many parameters a second look of this config has for a latent of this size."""
        def size(sizes) -> int:
            return sum(a * b + b for a, b in zip(sizes[:-1], sizes[1:], strict=True))

        return self.members * (size([SAMPLE_FEATURES + latent, *self.hidden])
                               + size([self.hidden[-1] + 2 * latent + 1, *self.after, latent]))


@dataclass
class Guess:
    """A guess z₁ read at the samples: what every look of a step reads besides the samples."""

    z1: torch.Tensor
    """The guess ``(B, latent)``."""
    parts: list[slice]
    """The parts the samples go through in."""
    predicted: list[torch.Tensor]
    """ŷ, the guess's decoding at each part's samples ``(B, part, 3)``."""
    gradient: torch.Tensor
    """The gradient of the samples' mean cosine-weighted L1 at z₁ ``(B, latent)``."""


def read_guess(coords: torch.Tensor, values: torch.Tensor, cos_in: torch.Tensor, z1: torch.Tensor,
               decoder: nn.Module, chunk: int) -> Guess:
    """Decodes z₁ at the samples, part by part, and takes the gradient of their loss at it. Nothing read here passes
    a gradient back, to z₁ or to the decoder."""
    n = values.shape[1]
    parts = [slice(begin, min(begin + chunk, n)) for begin in range(0, n, chunk)]
    with torch.enable_grad():
        z1_leaf = z1.detach().requires_grad_(True)
        params = decoder(z1_leaf)
        gradient, predicted = torch.zeros_like(z1), []
        for part in parts:
            predicted_part = nbrdf_forward(params, coords[:, part])
            error = ((predicted_part - values[:, part]) * cos_in[:, part, None]).abs().sum() / (3 * n)
            gradient += torch.autograd.grad(error, z1_leaf, retain_graph=part is not parts[-1])[0]
            predicted.append(predicted_part.detach())
    return Guess(z1, parts, predicted, gradient)


class SecondLook(nn.Module):
    """``(coords, values, cos_in)`` of B materials' samples and their first guesses z₁ ``(B, latent)`` → z."""

    def __init__(self, latent: int, config: SecondLookConfig):
        super().__init__()
        self.per_sample = nn.Sequential(mlp([SAMPLE_FEATURES + latent, *config.hidden]), nn.ReLU())
        self.after_pool = mlp([config.hidden[-1] + 2 * latent + 1, *config.after, latent])
        last = cast(nn.Linear, self.after_pool[-1])
        nn.init.zeros_(last.weight)  # Δz = 0: the untrained second look is the first
        nn.init.zeros_(last.bias)

    def forward(self, coords: torch.Tensor, values: torch.Tensor, cos_in: torch.Tensor, z1: torch.Tensor,
                decoder: nn.Module, chunk: int = 1 << 16) -> torch.Tensor:
        """``coords`` ``(B, N, 6)``, mapped ``values`` ``(B, N, 3)``, ``cos_in`` ``(B, N)``, ``z1`` ``(B, latent)``;
        ``decoder`` the model's (z → NBRDF parameters). The decoder's reading of z₁ passes no gradient back
        (:func:`read_guess`). The samples go through in parts of ``chunk`` (a whole table is 1.1 million)."""
        return self.answer(coords, values, cos_in, read_guess(coords, values, cos_in, z1, decoder, chunk))

    def answer(self, coords: torch.Tensor, values: torch.Tensor, cos_in: torch.Tensor, guess: Guess) -> torch.Tensor:
        """z from the samples and the guess read at them (:func:`read_guess`)."""
        n, z1 = values.shape[1], guess.z1
        pooled = sum(self.per_sample(torch.cat([values[:, part], coords[:, part], predicted,
                                                values[:, part] - predicted, cos_in[:, part, None],
                                                z1[:, None].expand(-1, predicted.shape[1], -1)], dim=-1)).sum(dim=1) / n
                     for part, predicted in zip(guess.parts, guess.predicted, strict=True))
        length = guess.gradient.norm(dim=-1, keepdim=True).clamp_min(1e-12)
        return z1 + self.after_pool(torch.cat([pooled, z1, guess.gradient / length, length.log()], dim=-1))


class LookMean(nn.Module):
    """Several second looks of one model (:attr:`SecondLookConfig.members`): called as a :class:`SecondLook` is, z is
    the mean of their answers. The guess is decoded and its gradient taken once for all of them."""

    def __init__(self, latent: int, config: SecondLookConfig):
        super().__init__()
        self.members = nn.ModuleList(SecondLook(latent, config) for _ in range(config.members))

    def looks(self) -> list[SecondLook]:
        """The members, typed."""
        return [cast(SecondLook, member) for member in self.members]

    def forward(self, coords: torch.Tensor, values: torch.Tensor, cos_in: torch.Tensor, z1: torch.Tensor,
                decoder: nn.Module, chunk: int = 1 << 16) -> torch.Tensor:
        """As :meth:`SecondLook.forward`: the mean of the members' answers from one reading of the guess."""
        guess = read_guess(coords, values, cos_in, z1, decoder, chunk)
        return torch.stack([look.answer(coords, values, cos_in, guess) for look in self.looks()]).mean(dim=0)


def build_second_look(latent: int, config: SecondLookConfig) -> SecondLook | LookMean:
    """The second look a config gives: one network, or with several members their :class:`LookMean` (one look's
    weights keep the names they had before members existed)."""
    return SecondLook(latent, config) if config.members == 1 else LookMean(latent, config)


def look_weights(states: list[dict[str, torch.Tensor]]) -> dict[str, torch.Tensor]:
    """The state dicts of looks trained apart (each a :class:`SecondLook`'s) as a model's ``second_look.*`` weights:
    one look's under its own names, several as a :class:`LookMean`'s members, in the order given."""
    prefixes = ["second_look."] if len(states) == 1 else [f"second_look.members.{i}." for i in range(len(states))]
    return {prefix + name: value for prefix, state in zip(prefixes, states, strict=True) for name, value in state.items()}
