"""One optimisation step, and the one place where the loss is composed.

Training (:mod:`.loop`) and the step timing (``benches/step_timing.py``) both call
:func:`optimisation_step`, so what is timed is what trains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from ..models.losses import FrequencyLoss, LossConfig, latent_penalty, reconstruction_loss, weight_penalty
from ..models.nbrdf import nbrdf_forward


@dataclass
class LossTerms:
    """The total loss (a tensor to differentiate) and each term's value (for the log)."""

    total: torch.Tensor
    logged: dict[str, float]
    parts: dict[str, torch.Tensor]
    """Each term as a tensor (``rec``, ``w``, ``z``, ``fre``), the weights applied except η."""
    gradient_ratio: float | None = None
    """‖∇(η·L_fre)‖ / ‖∇L_rec‖, where :func:`optimisation_step` was asked to measure it."""

    @property
    def not_finite(self) -> list[str]:
        """Names of the terms that are NaN or infinite (``total`` included)."""
        bad = [name for name, value in self.logged.items() if not math.isfinite(value)]
        return bad or ([] if torch.isfinite(self.total) else ["total"])


def decoding_terms(z: torch.Tensor, params: list[torch.Tensor], query, loss: LossConfig) -> dict[str, torch.Tensor]:
    """L_rec of the NBRDFs ``params`` decoded from ``z`` on ``query``, and the weight and latent penalties (weighted):
    the loss of a decoding, whether z came from the encoder or is free (:mod:`.decoder_fit`)."""
    return {
        "rec": reconstruction_loss(nbrdf_forward(params, query.coords), query.values, query.cos_in, loss.kind),
        "w": loss.lambda_weights * weight_penalty(params, loss.weight_penalty),
        "z": loss.lambda_latent * latent_penalty(z),
    }


def loss_terms(network, frequency: FrequencyLoss | None, loss: LossConfig, context, query,
               true_coefficients: torch.Tensor | None, truth_mask: torch.Tensor | None = None) -> LossTerms:
    """L = L_rec + λ1 · weights + λ2 · latents + η · L_fre (L_fre only with ``frequency`` and the truth).

    ``truth_mask`` ``(B,)`` bool: L_fre over the materials whose truth is known only (augmented
    batches); with none known the step has no L_fre term.
    """
    z, params = network(context.encoder_input())
    terms = decoding_terms(z, params, query, loss)
    if frequency is not None and true_coefficients is not None:
        if truth_mask is None:
            terms["fre"] = frequency(params, true_coefficients)
        elif truth_mask.any():
            terms["fre"] = frequency([p[truth_mask] for p in params], true_coefficients[truth_mask])
    total = terms["rec"] + terms["w"] + terms["z"] + loss.eta * terms.get("fre", 0.0)
    return LossTerms(total, {name: float(value.detach()) for name, value in terms.items()}, terms)


def gradient_norm_ratio(network, terms: LossTerms, eta: float) -> float:
    """‖∇(η·L_fre)‖ / ‖∇L_rec‖ over the network's parameters: the strength η gives L_fre."""
    params = [p for p in network.parameters() if p.requires_grad]
    norms = []
    for value in (eta * terms.parts["fre"], terms.parts["rec"]):
        grads = torch.autograd.grad(value, params, retain_graph=True, allow_unused=True)
        norms.append(math.sqrt(sum(float(g.square().sum()) for g in grads if g is not None)))
    return norms[0] / norms[1] if norms[1] > 0 else math.inf


def optimisation_step(network, frequency: FrequencyLoss | None, optimizer: torch.optim.Optimizer, loss: LossConfig,
                      grad_clip: float, context, query, true_coefficients: torch.Tensor | None, *,
                      measure_gradients: bool = False, truth_mask: torch.Tensor | None = None) -> LossTerms:
    """Computes the loss and, when every term is finite, takes one optimiser step (else none).

    ``measure_gradients``: also set ``terms.gradient_ratio`` (two more backward passes) when
    L_fre is part of the loss. ``truth_mask`` as in :func:`loss_terms`.
    """
    terms = loss_terms(network, frequency, loss, context, query, true_coefficients, truth_mask)
    if terms.not_finite:
        return terms
    if measure_gradients and "fre" in terms.parts and loss.eta > 0:
        terms.gradient_ratio = gradient_norm_ratio(network, terms, loss.eta)
    optimizer.zero_grad(set_to_none=True)
    terms.total.backward()
    if grad_clip > 0:
        torch.nn.utils.clip_grad_norm_(network.parameters(), grad_clip)
    optimizer.step()
    return terms
