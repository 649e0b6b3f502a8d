"""Two refinement budgets on real measurements, paired over materials and sample draws.

    python research/studies/budget_change.py ../shared/data/rgl-measured/*.bsdf --seeds 0 1 2 \\
        --out research/results/real/budget_change.json

For each measurement and each seed (a draw of ``--samples`` random valid MERL bins): the shipped
model reconstructs with the budgets before chart 8c and with today's (:data:`BEFORE` against
``frenbrdf.models.reconstruct.BUDGETS``), each result rendered against the render of the
measurement itself. Prints and writes the mean change in PSNR and ΔE with a 95 % paired t-interval
twice: over the material × seed pairs (``pairs``: draws of one material are not independent, so this
interval is the optimistic one) and over the materials' means (``materials``: the honest one with
few materials).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

from frenbrdf import Model
from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io import read_material
from frenbrdf.io.atomic import save_json
from frenbrdf.io.sampling import sample_bins, truth_samples
from frenbrdf.models.reconstruct import BUDGETS, RefineConfig
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

#: The budgets before chart 8c (charts 8 and 8b): constant rates, 100 latent steps.
BEFORE = {"latent": RefineConfig(latent_steps=100), "full": RefineConfig(latent_steps=100, weight_steps=1000)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="+", help=".bsdf files")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--resolution", type=int, default=256)
    parser.add_argument("--out", required=True, help="JSON file of every pair and the intervals")
    args = parser.parse_args(argv)
    model, scene = Model.pretrained(), Scene(resolution=args.resolution)
    mask, pairs = material_mask(scene), []
    for path in map(Path, args.measurements):
        truth = read_material(path)
        table, truth_image = truth.table(), tonemap(render_linear(truth, scene))
        for seed in args.seeds:
            rng = np.random.default_rng(seed)
            samples = truth_samples(truth, sample_bins(table, rng, args.samples), rng)
            for budget in BEFORE:
                metrics = {}
                for label, config in (("before", BEFORE[budget]), ("after", BUDGETS[budget])):
                    _, image, _ = refined_reconstruction(model, samples, scene, dataclasses.replace(config, seed=seed))
                    metrics[label] = image_metrics(truth_image, image, mask)
                pairs.append({"material": path.stem, "seed": seed, "budget": budget, **metrics})
                print(path.stem, seed, budget, " ".join(f"{k} {m['psnr']:.2f} dB ΔE {m['delta_e']:.2f}"
                                                        for k, m in metrics.items()), flush=True)
    def change(budget, key, per_material):
        chosen = [p for p in pairs if p["budget"] == budget]
        if not per_material:
            return paired_interval([p["after"][key] - p["before"][key] for p in chosen])
        materials = dict.fromkeys(p["material"] for p in chosen)
        return paired_interval([np.mean([p["after"][key] - p["before"][key] for p in chosen if p["material"] == m])
                                for m in materials])

    summary = {over: {budget: {key: change(budget, key, over == "materials") for key in ("psnr", "delta_e")}
                      for budget in BEFORE} for over in ("pairs", "materials")}
    save_json(Path(args.out), {"command": " ".join(sys.argv), "pairs": pairs, "change": summary})
    print(summary)
    return 0


if __name__ == "__main__":
    sys.exit(main())
