"""The hypernetwork decoder: a latent z → the weights of one NBRDF."""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn

from .encoder import MAX_LAYERS, MAX_WIDTH, mlp


@dataclass
class DecoderConfig:
    """One MLP head per NBRDF parameter tensor (latent → hidden → numel)."""

    hidden: tuple[int, ...] = (128, 128)
    """Hidden widths of every head."""
    last_layer_scale: float = 1.0
    """Factor on the default initialisation of each head's last weight matrix. At 0.1 (HyperBRDF's
    habit of starting small) every latent decodes to nearly the same NBRDF and, at the demo's 800
    steps, the decoder never learns to vary colour: purple, green and pink come back beige even with
    the latent optimised per material. At 1.0 the latent steers the NBRDF from the first step
    (research/colour.md)."""

    def __post_init__(self):
        self.hidden = tuple(int(h) for h in self.hidden)
        if min(self.hidden, default=1) < 1 or not (self.last_layer_scale > 0 and math.isfinite(self.last_layer_scale)):
            raise ValueError(f"decoder sizes and last_layer_scale must be positive, got {self}")
        if max(self.hidden, default=1) > MAX_WIDTH or len(self.hidden) > MAX_LAYERS:
            raise ValueError(f"decoder.hidden must be at most {MAX_LAYERS} widths in 1 … {MAX_WIDTH}, got {self.hidden}")


class HyperNetwork(nn.Module):
    """``z (B, latent)`` → a list of NBRDF parameter tensors ``(B, *shape)``.

    Each head's last layer starts at torch's default scale times ``last_layer_scale`` with its
    bias set to a standard initialisation of the NBRDF tensor, so every latent first decodes
    to a well-conditioned random NBRDF around a shared one. The NBRDF's output-layer biases
    start at zero: the mean first prediction is the mapped value 0, i.e. the reference BRDF.
    """

    def __init__(self, latent: int, shapes: list[tuple[int, ...]], config: DecoderConfig):
        super().__init__()
        self.shapes = [tuple(shape) for shape in shapes]
        heads = [mlp([latent, *config.hidden, math.prod(shape)]) for shape in self.shapes]
        self.heads = nn.ModuleList(heads)
        with torch.no_grad():
            for index, (head, shape) in enumerate(zip(heads, self.shapes, strict=True)):
                last = head[-1]
                assert isinstance(last, nn.Linear)
                last.weight.mul_(config.last_layer_scale)
                output_layer = index >= len(self.shapes) - 2
                if len(shape) == 2 and not output_layer:
                    bound = 1.0 / math.sqrt(shape[1])  # torch.nn.Linear's default
                    last.bias.uniform_(-bound, bound)
                else:
                    last.bias.zero_()

    def forward(self, z: torch.Tensor) -> list[torch.Tensor]:
        return [head(z).reshape(z.shape[0], *shape) for head, shape in zip(self.heads, self.shapes, strict=True)]


class FrozenDecoder:
    """A frozen :class:`HyperNetwork`'s forward pass and its pullback to z, written out: the heads' first layers as
    one matrix product (they all read z), each hidden layer after it as one batched product, the last layers one
    product a head, and the gradient back to z by the same products transposed. The same values as ``decoder(z)``
    and autograd up to the order of float32 sums, in a fraction of the time: test-time refinement's latent stage
    decodes one z thousands of times, where autograd's small operations were most of a step
    (research/performance.md). The weights are copied once: the decoder must not change while this is in use."""

    def __init__(self, decoder: HyperNetwork):
        linears = [[layer for layer in head.children() if isinstance(layer, nn.Linear)] for head in decoder.heads]
        with torch.no_grad():
            self.first = (torch.cat([head[0].weight for head in linears]), torch.cat([head[0].bias for head in linears]))
            self.hidden = [(torch.stack([head[i].weight for head in linears]),
                            torch.stack([head[i].bias for head in linears])[:, None])
                           for i in range(1, len(linears[0]) - 1)]
            self.last = [(head[-1].weight.detach().clone(), head[-1].bias.detach().clone()) for head in linears]
        self.sizes = [math.prod(shape) for shape in decoder.shapes]
        self._active: list[torch.Tensor] = []

    @torch.no_grad()
    def weights(self, z: torch.Tensor) -> torch.Tensor:
        """The decoded NBRDF of one ``z`` ``(1, latent)``: every tensor flattened, in order ``(numel,)``; keeps
        which units were active for :meth:`pullback`."""
        x = torch.relu(torch.nn.functional.linear(z, *self.first)).reshape(len(self.last), 1, -1)  # (heads, 1, width)
        self._active = [x > 0]
        for weight, bias in self.hidden:
            x = torch.relu(torch.baddbmm(bias, x, weight.transpose(1, 2)))
            self._active.append(x > 0)
        return torch.cat([torch.addmm(bias, x[i], weight.t())[0] for i, (weight, bias) in enumerate(self.last)])

    @torch.no_grad()
    def pullback(self, gradient: torch.Tensor) -> torch.Tensor:
        """The gradient with respect to z ``(1, latent)`` of a loss whose gradient with respect to the last
        :meth:`weights` is ``gradient`` ``(numel,)``."""
        parts = torch.split(gradient, self.sizes)
        x = torch.stack([part[None] @ weight for part, (weight, _) in zip(parts, self.last, strict=True)])
        for (weight, _), active in zip(reversed(self.hidden), reversed(self._active[1:]), strict=True):
            x = torch.bmm(x * active, weight)
        return (x * self._active[0]).reshape(1, -1) @ self.first[0]
