"""The seam along the plane of incidence: how far apart a reconstruction's values at φ_d = 0 and φ_d = π lie.

    python research/studies/seam.py ../shared/data/rgl-measured/*.bsdf [--model RUN] [--budgets none latent full]
        --json research/results/seam/seam.json

The NBRDF's input folds D by reciprocity (D → (−D_x, −D_y, D_z) where D_y < 0: ``nbrdf.fold_difference``), so
where a light, the view and the normal are coplanar (φ_d crosses 0 or π), a render's pixels on one side ask the
network about φ_d near 0 and those on the other about φ_d near π. Those agree for a BRDF with f(φ_d) = f(π − φ_d)
(isotropic, reciprocal and mirror-symmetric); whatever a network puts between them is a seam in every render, a
line from the sphere's centre through each light's highlight. Reported per material: the median and 90th
percentile, over a grid of (θ_h, θ_d) with both directions above the horizon, of the step
|ln(f(φ_d = s + ε) + c) − ln(f(φ_d = s − ε) + c)| across the seams s = 0 and π (ε = 0.5°, c = 0.01 1/sr, the
channels' mean), for the measurement as measured (a ``.bsdf`` is evaluated without a fold: its step is what 1° of
φ_d changes) and for the shipped model's reconstructions from 4,000 random bins (``--budgets``: by default the
encoder, ``latent`` and ``full``; a budget ``NAME@FIELD=VALUE`` as compare_models.py reads it).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from compare_models import budget_config
from tqdm import tqdm

import frenbrdf
from frenbrdf.io.atomic import save_json

FLOOR = 0.01  # 1/sr: differences among values far below a diffuse white's 0.3 do not show
#: Half a degree either side of a seam: across φ_d = 0, D = (x, ±ε, z), and the fold turns (x, −ε, z) into (−x, ε, z).
EPSILON = np.radians(0.5)


def seam_pairs(n: int = 40) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """A (θ_h, θ_d) grid on both sides of both seams: φ_d = ±ε about 0 and π ± ε about π (a render crosses them
    where light, view and normal are coplanar), as (ω_i, ω_o) pairs, kept where every pair lies above the horizon."""
    theta = (np.arange(n) + 0.5) / n * np.pi / 2 * 0.98
    theta_h, theta_d = (grid.ravel() for grid in np.meshgrid(theta, theta, indexing="ij"))
    sides = []
    for offset in (EPSILON, -EPSILON):
        phi_d = np.concatenate([np.full_like(theta_h, offset), np.full_like(theta_h, np.pi - offset)])
        angles = np.stack([np.tile(theta_h, 2), np.zeros_like(phi_d), np.tile(theta_d, 2), phi_d], axis=-1)
        sides.append(frenbrdf.rusinkiewicz_to_directions(angles))
    above = np.ones(len(sides[0][0]), dtype=bool)
    for wi, wo in sides:
        above &= (wi[:, 2] > 0.02) & (wo[:, 2] > 0.02)
    return tuple((wi[above], wo[above]) for wi, wo in sides)


def jumps(brdf, side, other) -> dict:
    """The median and 90th percentile over the grid of the log step from one side of the seams to the other."""
    step = np.abs(np.log(np.mean(brdf(*side), axis=-1) + FLOOR) - np.log(np.mean(brdf(*other), axis=-1) + FLOOR))
    return {"median": float(np.median(step)), "p90": float(np.quantile(step, 0.9))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("measurements", nargs="+", type=Path)
    parser.add_argument("--model", default="pretrained", help="a training run folder, or the shipped model")
    parser.add_argument("--budgets", nargs="+", default=["none", "latent", "full"])
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    model = frenbrdf.Model.pretrained() if args.model == "pretrained" else frenbrdf.Model.load(args.model)
    side, other = seam_pairs()
    rows = {}
    for path in tqdm(args.measurements, desc="materials"):
        measured = frenbrdf.read_bsdf(path)
        samples = frenbrdf.read_samples(path, samples=4000, seed=0)
        row = {"measured": jumps(measured, side, other)}
        for budget in args.budgets:
            result = model.reconstruct(samples.values, (samples.wi, samples.wo), refine=budget_config(budget))
            row[budget] = jumps(result.nbrdf, side, other)
        rows[path.stem] = row
        print(path.stem, "  ".join(f"{k} {v['median']:.3f}/{v['p90']:.3f}" for k, v in row.items()))
    summary = {kind: {stat: float(np.median([row[kind][stat] for row in rows.values()])) for stat in ("median", "p90")}
               for kind in ("measured", *args.budgets)}
    print("median over materials:", summary)
    if args.json:
        save_json(args.json, {"model": args.model, "floor": FLOOR, "pairs": len(side[0]), "materials": rows,
                              "summary": summary})


if __name__ == "__main__":
    main()
