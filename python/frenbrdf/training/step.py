"""One optimisation step, and the one place where the loss is composed.

Training (:mod:`.loop`) and the step timing (:mod:`frenbrdf.timing`) both call
:func:`optimisation_step`, so what is timed is what trains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from ..losses import FrequencyLoss, LossConfig, latent_penalty, reconstruction_loss, weight_penalty
from ..models.nbrdf import nbrdf_forward


@dataclass
class LossTerms:
    """The total loss (a tensor to differentiate) and each term's value (for the log)."""

    total: torch.Tensor
    logged: dict[str, float]

    @property
    def not_finite(self) -> list[str]:
        """Names of the terms that are NaN or infinite (``total`` included)."""
        bad = [name for name, value in self.logged.items() if not math.isfinite(value)]
        return bad or ([] if torch.isfinite(self.total) else ["total"])


def loss_terms(network, frequency: FrequencyLoss | None, loss: LossConfig, context, query,
               true_coefficients: torch.Tensor | None) -> LossTerms:
    """L = L_rec + λ1 · weights + λ2 · latents + η · L_fre (L_fre only with ``frequency`` and the truth)."""
    z, params = network(context.encoder_input())
    terms = {
        "rec": reconstruction_loss(nbrdf_forward(params, query.coords), query.values, query.cos_in, loss.kind),
        "w": loss.lambda_weights * weight_penalty(params),
        "z": loss.lambda_latent * latent_penalty(z),
    }
    if frequency is not None and true_coefficients is not None:
        terms["fre"] = frequency(params, true_coefficients)
    total = terms["rec"] + terms["w"] + terms["z"] + loss.eta * terms.get("fre", 0.0)
    return LossTerms(total, {name: float(value.detach()) for name, value in terms.items()})


def optimisation_step(network, frequency: FrequencyLoss | None, optimizer: torch.optim.Optimizer, loss: LossConfig,
                      grad_clip: float, context, query, true_coefficients: torch.Tensor | None) -> LossTerms:
    """Computes the loss and, when every term is finite, takes one optimiser step (else none)."""
    terms = loss_terms(network, frequency, loss, context, query, true_coefficients)
    if terms.not_finite:
        return terms
    optimizer.zero_grad(set_to_none=True)
    terms.total.backward()
    if grad_clip > 0:
        torch.nn.utils.clip_grad_norm_(network.parameters(), grad_clip)
    optimizer.step()
    return terms
