"""Adam written out for test-time refinement's latent stage (:mod:`frenbrdf.models.reconstruct`)."""

from __future__ import annotations

import torch


class Adam:
    """``torch.optim.Adam``'s steps (its defaults, L2 weight decay per tensor), the same arithmetic as its
    single-tensor form, on tensors whose ``.grad`` a step leaves. Not torch's own: constructing any ``torch.optim``
    optimizer first imports ``torch._dynamo``, about 2 s, more than the whole latent stage (research/performance.md)."""

    BETAS, EPS = (0.9, 0.999), 1e-8

    def __init__(self, parameters: list[torch.Tensor], decays: list[float]):
        self.parameters, self.decays, self.taken = parameters, decays, 0
        self.moments = [(torch.zeros_like(p), torch.zeros_like(p)) for p in parameters]

    @torch.no_grad()
    def step(self, lr: float) -> None:
        (beta1, beta2), self.taken = self.BETAS, self.taken + 1
        step_size = lr / (1 - beta1 ** self.taken)
        correction2 = (1 - beta2 ** self.taken) ** 0.5  # as torch's; math.sqrt differs in the last bit at times
        for p, decay, (mean, square) in zip(self.parameters, self.decays, self.moments, strict=True):
            assert p.grad is not None, "a step leaves the gradient in .grad"
            grad = p.grad.add(p, alpha=decay) if decay else p.grad  # as torch's: one rounding, not two
            mean.lerp_(grad, 1 - beta1)
            square.mul_(beta2).addcmul_(grad, grad, value=1 - beta2)
            p.addcdiv_(mean, (square.sqrt() / correction2).add_(self.EPS), value=-step_size)
