"""One arm of the seam-tie study (research/results/seam-tie): train the NBRDF baseline at the demo's length with
today's loss (``fold``) or with a term that ties each decoded NBRDF's two sides of the reciprocity fold's edge
(``tied``, at ``--weight``: a run named ``tied@WEIGHT`` unless the weight is ``TIE_WEIGHT``), then read its test
split and the seam across the plane of incidence on the 19 measurements.

    python research/studies/seam_tie.py --arm fold|tied --seed 0 --data BANK --work WORK [--weight 0.3]

The fold (``frenbrdf.models.nbrdf.fold_difference``) makes every decoded BRDF reciprocal but lets the network put a
step between φ_d = 0 and φ_d = π at the same (θ_h, θ_d), where a true reciprocal BRDF is continuous: the inputs
(H, (x, 0, z)) and (H, (−x, 0, z)) are one configuration and its reverse (research/results/seam). ``tied`` adds
``TIE_WEIGHT`` · mean |N(a) − N(b)| over ``TIE_PAIRS`` such pairs a step (drawn from a fixed pool above the horizon by
a generator of the run's own, so both arms draw the same batches) to each training step's loss, in this process
only; validation, the choice of the best epoch and every reading are today's. Nothing in the package changes.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

import frenbrdf
from frenbrdf.models.nbrdf import nbrdf_coordinates, nbrdf_forward
from frenbrdf.training import step

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paired_arms import train_and_read  # noqa: E402

#: The tie's weight against L_rec (a mean absolute error in the mapped space, as L_rec's) and its pairs a step.
TIE_WEIGHT = 1.0
TIE_PAIRS = 256
POOL = 8192


def edge_pool(seed: int) -> tuple[torch.Tensor, torch.Tensor]:
    """``POOL`` NBRDF inputs on the fold's edge (φ_d = 0, random θ_h and θ_d with both directions above the horizon)
    and the same inputs with D_x negated (φ_d = π: the reverse pair before the fold), each ``(POOL, 6)``."""
    rng = np.random.default_rng(1000 + seed)
    kept: list[np.ndarray] = []
    while sum(len(k) for k in kept) < POOL:
        theta = rng.uniform(0.0, np.pi / 2, size=(4 * POOL, 2))
        angles = np.stack([theta[:, 0], np.zeros(len(theta)), theta[:, 1], np.zeros(len(theta))], axis=-1)
        wi, wo = frenbrdf.rusinkiewicz_to_directions(angles)
        above = (wi[:, 2] > 0.02) & (wo[:, 2] > 0.02)
        kept.append(nbrdf_coordinates(wi[above], wo[above]))
    side = np.concatenate(kept)[:POOL]
    side[:, 4] = 0.0  # D_y exactly 0: the edge itself
    other = side.copy()
    other[:, 3] *= -1.0
    return torch.from_numpy(side.astype(np.float32)), torch.from_numpy(other.astype(np.float32))


def use_tie(seed: int, weight: float = TIE_WEIGHT) -> None:
    """Adds the tie at ``weight`` to every training step's weight-penalty term (not under ``torch.no_grad``:
    validation is today's)."""
    side, other = edge_pool(seed)
    generator = torch.Generator().manual_seed(2000 + seed)
    plain_terms = step.decoding_terms

    def tied_terms(z, params, query, loss):
        terms = plain_terms(z, params, query, loss)
        if torch.is_grad_enabled():
            rows = torch.randint(POOL, (TIE_PAIRS,), generator=generator)
            batch = params[0].shape[0]
            a = nbrdf_forward(params, side[rows][None].expand(batch, -1, -1))
            b = nbrdf_forward(params, other[rows][None].expand(batch, -1, -1))
            terms["w"] = terms["w"] + weight * (a - b).abs().mean()
        return terms

    step.decoding_terms = tied_terms


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arm", choices=("fold", "tied"), required=True)
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--data", required=True, help="the bank (frenbrdf synth BANK --seed 1)")
    parser.add_argument("--work", type=Path, required=True)
    parser.add_argument("--measured", default="../shared/data/rgl-measured")
    parser.add_argument("--weight", type=float, default=TIE_WEIGHT, help="the tie's weight (arm tied)")
    args = parser.parse_args()
    arm = args.arm
    if args.arm == "tied":
        use_tie(args.seed, args.weight)
        arm = "tied" if args.weight == TIE_WEIGHT else f"tied@{args.weight:g}"
    train_and_read(arm, args.seed, args.data, args.work, Path(args.measured), ("none", "latent", "full"))


if __name__ == "__main__":
    main()
