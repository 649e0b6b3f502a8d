"""Weights that undo a sampling pattern's uneven coverage, for test-time refinement.

A device samples some regions of the BRDF's domain densely (around the mirror direction of each light) and others
thinly or not at all; random MERL bins, what the model trained on, cover the MERL table's index space evenly. The
loss over a device's samples then counts the dense regions many times over, and `latent` fits them at the expense of
the rest. :func:`coverage_weights` weighs each sample by the density random valid bins have at its place over the
density the samples themselves have there, both k-nearest-neighbour estimates in that index space
(√(θ_h / (π/2)), θ_d / (π/2), φ_d mod π / π), so that the weighted loss estimates the loss over the whole table, as
random bins' plain loss does. Taking the ratio of two estimates made the same way cancels the low estimates at the
domain's edges (research/results/latent-gap/README.md, research/results/latent-coverage/README.md).

Where the samples say nothing at all (a device that sees only the mirror directions), no weight helps: `latent` may
move the material there freely, and does (a dark olive base turned bright blue by specular-only pairs).
:func:`uncovered_bins` names random valid bins far from every sample, the places where `latent` could
hold the encoder's guess instead (``RefineConfig.anchor``; measured not to help on average:
research/results/latent-anchor/README.md).

The neighbours come from SciPy's k-d tree: the package's own k-NN core (kiddo) holds unit vectors, and these places
are not.
"""

from __future__ import annotations

import functools
import numbers

import numpy as np
from scipy.spatial import cKDTree

from ..io.merl import SHAPE, merl_above_horizon
from ..numerics.coords import directions_to_rusinkiewicz

#: Weights are clipped at this many times their mean (then scaled back to mean 1): a lone sample far from the others
#: stands for a region, not for all of it.
MAX_WEIGHT = 10.0
#: The largest k: neighbours beyond a thousand describe no local density.
MAX_K = 1024
#: Neighbour distances and indices a k-NN query holds at once (16 bytes each: 256 MB).
QUERY_VALUES = 1 << 24
#: Random valid bins whose density is the reference (drawn once, from a fixed seed).
REFERENCE_BINS = 20_000
#: Where every pair's half vector lies within this angle (degrees) of the normal, the pairs show the material only
#: around its mirror reflection (a device of the ``specular`` pattern's kind: 18.5° at most) and
#: :func:`coverage_summary` warns: what the material does away from it, its base colour, is a guess.
MIRROR_ONLY_DEGREES = 25.0
#: Random valid bins :func:`uncovered_bins` looks at (drawn once, from another fixed seed).
ANCHOR_BINS = 2_048
#: How far (in :func:`index_space`, whose sides are 1) the nearest pair may lie before :func:`uncovered_bins` counts a
#: bin as one the pairs say nothing of: about the spacing of 1,000 random bins.
ANCHOR_RADIUS = 0.1


def coverage_weights(wi, wo, k: int) -> np.ndarray:
    """Per pair ``(N,)``: random valid MERL bins' density over the pairs' own at the pair (k-NN estimates), clipped at
    :data:`MAX_WEIGHT` times their mean, then scaled to mean 1. ``wi``, ``wo``: ``(N, 3)`` directions above the
    surface. Fewer than ``k + 1`` pairs all weigh 1."""
    if isinstance(k, bool) or not isinstance(k, numbers.Integral) or not 1 <= k <= MAX_K:
        raise ValueError(f"k must be an integer from 1 to {MAX_K}, got {k!r}")
    points = index_space(wi, wo)
    if len(points) <= k:
        return np.ones(len(points))  # too few pairs to tell dense from thin
    # The k-th neighbour other than the pair itself; a density is k / (count · distance³).
    own = _kth_distance(cKDTree(points), points, k + 1)
    reference = _kth_distance(cKDTree(_reference_bins()), points, k)
    weights = np.maximum(own, 1e-12) ** 3 / np.maximum(reference, 1e-12) ** 3
    weights /= weights.mean()
    weights = np.minimum(weights, MAX_WEIGHT)
    return weights / weights.mean()


def uncovered_bins(wi, wo) -> tuple[np.ndarray, np.ndarray]:
    """Where the pairs say nothing: flat indices of random valid MERL bins ``(M,)`` whose nearest pair lies farther
    than :data:`ANCHOR_RADIUS` in :func:`index_space`, and how far ``(M,)`` in (0, 1]: the distance over the radius,
    less 1, at most 1 (so 1 from twice the radius on). ``wi``, ``wo``: ``(N, 3)`` directions above the surface, N ≥ 1.
    1,500 random bins leave almost none; a device that sees only the mirror directions leaves half the table."""
    return _far_bins(index_space(wi, wo))


def _far_bins(places: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`uncovered_bins` of pairs at ``places`` (:func:`index_space`)."""
    nearest = cKDTree(places).query(_anchor_places(), k=1)[0]
    remoteness = np.minimum(nearest / ANCHOR_RADIUS - 1, 1.0)
    far = remoteness > 0
    return _anchor_bins()[far], remoteness[far]


def coverage_summary(wi, wo) -> dict:
    """What the pairs ``(N, 3)`` each show of a material, JSON-ready: the largest angle of their half vectors from
    the normal (degrees), the share of random valid bins that lie far from every pair (:func:`uncovered_bins`), and
    ``warnings``: what the pairs cannot tell, in words (empty where nothing is known to be missing)."""
    places = index_space(wi, wo)
    largest = float(np.degrees(places[:, 0].max() ** 2 * np.pi / 2))  # the place's first axis is √(θ_h / (π/2))
    warnings = []
    if largest < MIRROR_ONLY_DEGREES:
        warnings.append(f"every sample's half vector lies within {largest:.0f}° of the normal: the samples show the "
                        "material only around its mirror reflection, and its base colour (what it reflects away "
                        "from the mirror direction) is a guess. From such samples `latent` gave real measurements "
                        "back 5.3 dB worse than from random bins, some with the wrong base colour "
                        "(docs/results.md); sample away from the mirror direction too if you can")
    return {"largest_half_angle_deg": largest, "uncovered": len(_far_bins(places)[0]) / ANCHOR_BINS,
            "warnings": warnings}


def _kth_distance(tree: cKDTree, points: np.ndarray, k: int) -> np.ndarray:
    """The distance from each point to its k-th nearest in ``tree``, in chunks whose neighbour lists stay within
    :data:`QUERY_VALUES` values (a whole MERL table's 1.1 million pairs at k = 1024 would need 18 GB at once)."""
    rows = max(1, QUERY_VALUES // k)
    # k=[k] asks for the k-th neighbour alone, as a column even at k = 1 (a plain k=1 returns a flat array).
    return np.concatenate([tree.query(points[start:start + rows], k=[k])[0][:, 0]
                           for start in range(0, len(points), rows)])


def index_space(wi, wo) -> np.ndarray:
    """Pairs ``(N, 3)`` each → their place ``(N, 3)`` in the MERL table's index space scaled to [0, 1]³."""
    theta_h, _, theta_d, phi_d = np.asarray(directions_to_rusinkiewicz(wi, wo)).reshape(-1, 4).T
    return np.stack([np.sqrt(np.clip(theta_h / (np.pi / 2), 0.0, 1.0)), np.clip(theta_d / (np.pi / 2), 0.0, 1.0),
                     np.mod(phi_d, np.pi) / np.pi], axis=1)


@functools.cache
def _anchor_bins() -> np.ndarray:
    """:data:`ANCHOR_BINS` random valid bins' flat indices (the MERL table's θ_h, θ_d, φ_d grid)."""
    valid = np.flatnonzero(merl_above_horizon())
    return np.sort(np.random.default_rng(1).choice(valid, ANCHOR_BINS, replace=False))


@functools.cache
def _anchor_places() -> np.ndarray:
    """:func:`_anchor_bins`' centres in :func:`index_space`."""
    return (np.stack(np.unravel_index(_anchor_bins(), SHAPE[1:]), axis=1) + 0.5) / np.array(SHAPE[1:])


@functools.cache
def _reference_bins() -> np.ndarray:
    """:data:`REFERENCE_BINS` random valid bins' centres in :func:`index_space`."""
    valid = np.argwhere(merl_above_horizon())
    chosen = valid[np.random.default_rng(0).choice(len(valid), REFERENCE_BINS, replace=False)]
    return (chosen + 0.5) / np.array(SHAPE[1:])
