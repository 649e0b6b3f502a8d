"""Exploratory (no rule): does ``latent`` through the device patterns gain from 800 steps instead of 200?

    OMP_NUM_THREADS=2 python research/results/patterns-measured/latent_steps.py local/spec/families

Version 6 on every third table of FOLDER (the seed-2 families), 1,500 samples of each pattern (draw 0), ``latent``
at its default schedule with 200 and with 800 steps; prints the per-material PSNR difference, its mean, spread and
standard error per pattern (research/notebook.md, 2026-11-28).
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np

from frenbrdf.io import read_material
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.io.sampling import as_table
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import condition_rng  # noqa: E402

PATTERNS = ("uniform", "in-plane", "image-based", "merl-bins")


def main() -> None:
    model, scene = load_model("pretrained"), Scene(resolution=128)
    mask = material_mask(scene)
    paths = sorted(Path(sys.argv[1]).glob("*.binary"))[::3]
    short = dataclasses.replace(refine_config("latent"), seed=0, progress=False)
    budgets = {"200": short, "800": dataclasses.replace(short, latent_steps=800)}
    for pattern in PATTERNS:
        differences = []
        for path in paths:
            truth = read_material(path)
            truth_image = tonemap(render_linear(truth, scene))
            drawn = pattern_samples(truth, pattern, 1500, condition_rng(0, pattern), table=as_table(truth))
            psnr = {name: image_metrics(truth_image, refined_reconstruction(model, drawn, scene, config)[1], mask)["psnr"]
                    for name, config in budgets.items()}
            differences.append(psnr["800"] - psnr["200"])
        d = np.array(differences)
        spread = d.std(ddof=1)
        print(f"{pattern}: {len(d)} materials, 800 − 200 steps {d.mean():+.2f} dB "
              f"(sd {spread:.2f}, se {spread / np.sqrt(len(d)):.2f})", flush=True)


if __name__ == "__main__":
    main()
