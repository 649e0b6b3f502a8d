"""The set encoder: DeepSets over (mapped RGB, H, D) samples, mean pooled into a latent.

DeepSets is z = ρ(mean φ(sample)). The paper's encoder (the default) has no ρ: z is the mean of
per-sample codes, a linear functional of the samples' distribution. ``EncoderConfig.pooled`` gives it
a ρ, an MLP after the mean, so that z can depend non-linearly on what the samples show together
(research/measurements.md measures what that does to the encoder's gap on real materials).

The plain mean estimates an expectation under the sampling distribution: a device that samples the
highlight densely moves z although the material is the same. ``EncoderConfig.pooling = "density"``
weights each sample's code by the inverse of a k-nearest-neighbour estimate of the samples' density in
their coordinates (H, D) (:func:`density_weights`), so that the pooled code approximates a mean over
the domain the samples cover rather than over the samples (docs/method.md, "Pooling").
``EncoderConfig.pooling = "attention"`` learns the weights instead: a small MLP scores each sample once per head,
a softmax over the set turns the scores into weights, and each head pools its share of the code's features with
them (its score layer starts at zero, so an untrained attention encoder is the plain mean).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np
import torch
from torch import nn

#: One sample: mapped RGB (3) and the NBRDF coordinates H, D (6).
SAMPLE_SIZE = 9
#: Where a sample's coordinates (H, D) lie in it: after the 3 mapped values.
COORDINATES = slice(3, 9)
#: How the per-sample codes may be pooled (:attr:`EncoderConfig.pooling`).
POOLINGS = ("mean", "density", "attention")
#: How several encoders of one latent space give one z (:attr:`frenbrdf.models.autoencoder.ModelConfig.encoder_choice`).
ENCODER_CHOICES = ("mean", "best-fit")
#: The dimension of the set the coordinates of an isotropic material's pairs fill: H (φ_h = 0) runs along an arc
#: (θ_h) and D over a sphere (θ_d, φ_d), a 3-dimensional set inside the 6 numbers. A k-NN density estimate there
#: scales as 1 / r_k³: so do the weights' powers (:func:`density_weights`).
DENSITY_DIMENSION = 3
#: A sample's k-NN radius is taken as at least this share of the set's median radius: ``k`` + 1 samples at one bin
#: (a pattern's pairs in one bin) get a small weight, not none.
RADIUS_FLOOR = 0.05
#: Points of the exhaustive k-NN search a chunk compares at once (on the GPU; a CPU set uses scipy's k-d tree).
_KNN_CHUNK = 1 << 24
#: Samples whose attention scores are computed at once (bounds the memory of encoding a whole table).
_SCORE_CHUNK = 1 << 16
#: The most neighbours :attr:`EncoderConfig.density_k` may name.
MAX_DENSITY_K = 256
#: The fields of :class:`EncoderConfig` that say how the codes are pooled: only attention has weights of its own
#: (:func:`pooling_fields_with_weights`).
POOLING_FIELDS = ("pooling", "density_k", "attention_heads")
#: Hidden width of attention pooling's score network (one hidden layer).
SCORE_HIDDEN = 64
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
    pooling: str = "mean"
    """How the per-sample codes are pooled: ``"mean"``, the plain mean (the paper's; models saved before this
    option load with it), or ``"density"``, each code weighted by the inverse of a k-NN estimate of the samples'
    density in (H, D) (:func:`density_weights`), so that the pooled code depends less on how the material was
    sampled. The weights are the same for every ρ; they carry no gradient and no parameters. Or ``"attention"``:
    weights learned from what each sample is and where it lies (a score network, :attr:`attention_heads`)."""
    density_k: int = 8
    """The neighbour whose distance estimates a sample's density with ``pooling="density"`` (the k of k-NN; a set of
    at most k samples uses its size − 1)."""
    attention_heads: int = 4
    """With ``pooling="attention"``: how many sets of weights; the pooled features (the latent, or the last hidden
    layer when there is a ρ) are cut into this many equal shares, each pooled with its head's weights."""

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
        if self.pooling not in POOLINGS:
            raise ValueError(f"encoder pooling must be one of {POOLINGS}, got {self.pooling!r}")
        if not 1 <= self.density_k <= MAX_DENSITY_K:
            raise ValueError(f"encoder density_k must lie in 1 … {MAX_DENSITY_K}, got {self.density_k}")
        heads = self.attention_heads
        if self.pooling == "attention" and not (isinstance(heads, int) and not isinstance(heads, bool) and heads >= 1
                                                and self.pooled_width % heads == 0):
            raise ValueError(f"encoder attention_heads must be a whole number ≥ 1 that divides the pooled width "
                             f"{self.pooled_width}, got {self.attention_heads!r}")

    @property
    def pooled_width(self) -> int:
        """How many features are pooled: the latent, or the last hidden layer when there is a ρ."""
        return self.hidden[-1] if self.pooled else self.latent


def pooling_fields_with_weights(config: dict) -> dict:
    """The pooling fields of an encoder config (a dict) that its weights depend on: attention's, whose score network
    has ``attention_heads`` outputs; none for the mean and density pooling, which have no weights."""
    if config.get("pooling") == "attention":
        return {"attention_heads": config.get("attention_heads")}
    return {}


def knn_radius(points: torch.Tensor, k: int, *, exhaustive: bool | None = None) -> torch.Tensor:
    """The distance from each point to its k-th nearest other point, ``(..., N, C)`` → ``(..., N)`` (Euclidean;
    ``1 ≤ k < N``). ``exhaustive``: compare every pair, in chunks (None: on a GPU; a CPU set is searched with
    scipy's k-d tree, which a set of a whole table of 1.1 million bins needs)."""
    n = points.shape[-2]
    if not 1 <= k < n:
        raise ValueError(f"k must lie in 1 … {n - 1} (the other points of a set of {n}), got {k}")
    flat = points.detach().reshape(-1, n, points.shape[-1])
    if not (flat.device.type != "cpu" if exhaustive is None else exhaustive):
        from scipy.spatial import cKDTree

        found = [cKDTree(p).query(p, k=[k + 1])[0][:, 0] for p in flat.double().numpy()]  # k + 1: itself first
        return torch.from_numpy(np.stack(found)).to(points.dtype).reshape(points.shape[:-1])
    rows = max(1, _KNN_CHUNK // (len(flat) * n))
    radii = [torch.cdist(flat[:, start:start + rows], flat).topk(k + 1, dim=-1, largest=False).values[..., k]
             for start in range(0, n, rows)]
    return torch.cat(radii, dim=-1).reshape(points.shape[:-1])


@torch.no_grad()
def density_weights(coordinates: torch.Tensor, k: int) -> torch.Tensor:
    """Weights ``(..., N)`` summing to 1 over each set of samples ``(..., N, C)``: each sample's share of the domain
    the set covers, ∝ r_k^3 with r_k its distance to its k-th nearest other sample (the inverse of the k-NN density
    estimate k / (N · volume of the ball of radius r_k) in the :data:`DENSITY_DIMENSION` dimensions the coordinates
    fill). r_k is taken as at least :data:`RADIUS_FLOOR` times the set's median. A set of one sample weighs it 1,
    a set of at most k uses k = N − 1; a set of identical samples is weighed evenly."""
    n = coordinates.shape[-2]
    if n == 1:
        return torch.ones(coordinates.shape[:-1], dtype=coordinates.dtype, device=coordinates.device)
    radius = knn_radius(coordinates, min(k, n - 1)).double()
    floor = RADIUS_FLOOR * radius.median(dim=-1, keepdim=True).values
    weights = torch.maximum(radius, floor) ** DENSITY_DIMENSION
    total = weights.sum(dim=-1, keepdim=True)
    even = torch.full_like(weights, 1.0 / n)
    return torch.where(total > 0, weights / total.clamp_min(torch.finfo(torch.float64).tiny), even).to(coordinates.dtype)


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
        self.pooling, self.density_k, self.heads = config.pooling, config.density_k, config.attention_heads
        if self.pooling == "attention":
            self.scores = mlp([SAMPLE_SIZE, SCORE_HIDDEN, self.heads])
            last = cast(nn.Linear, self.scores[-1])
            nn.init.zeros_(last.weight)  # even weights at the start: the plain mean
            nn.init.zeros_(last.bias)

    def weights(self, samples: torch.Tensor) -> torch.Tensor | None:
        """The pooling weights of the samples ``(B, N, 9)``, summing to 1 over the set: ``(B, N)`` with density
        pooling (:func:`density_weights`), ``(B, N, heads)`` with attention (:meth:`attention_weights`); None for the
        plain mean."""
        if self.pooling == "density":
            return density_weights(samples[..., COORDINATES], self.density_k)
        if self.pooling == "attention":
            return self.attention_weights(samples)
        return None

    def attention_weights(self, samples: torch.Tensor) -> torch.Tensor:
        """Each head's softmax over the set of its scores, ``(B, N, 9)`` → ``(B, N, heads)``; scored in chunks (a
        whole table is 1.1 million samples)."""
        scores = torch.cat([self.scores(chunk) for chunk in samples.split(_SCORE_CHUNK, dim=-2)], dim=-2)
        return scores.softmax(dim=-2)

    def pooled_features(self, samples: torch.Tensor, weights: torch.Tensor | None = None) -> torch.Tensor:
        """The pooled per-sample features, ``(B, N, 9)`` → ``(B, F)``: what ρ reads. The plain mean, or the sum
        weighted with :meth:`weights` (computed here unless given): attention weighs each head's share of F with
        that head's weights."""
        features = self.per_sample(samples)
        weights = self.weights(samples) if weights is None else weights
        if weights is None:
            return features.mean(dim=-2)
        if weights.ndim == features.ndim - 1:  # one weight per sample (density)
            return (weights.unsqueeze(-1) * features).sum(dim=-2)
        shares = features.unflatten(-1, (self.heads, -1))  # (B, N, heads, F / heads)
        return (weights.unsqueeze(-1) * shares).sum(dim=-3).flatten(-2)

    def forward(self, samples: torch.Tensor) -> torch.Tensor:
        return self.after_pool(self.pooled_features(samples))


class EncoderMean(nn.Module):
    """Several set encoders of one latent space; z is the mean of their latents (in training, and in
    :meth:`frenbrdf.Model.encode` unless ``ModelConfig.encoder_choice`` is ``"best-fit"``).

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
