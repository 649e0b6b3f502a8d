"""The latent-steps study's exploration (README.md; decides nothing): `latent` variants of MODEL (version 7's
packed files, from commit e3d07f8) on every third of the 45 families of seed 7, through random bins (4,000) and
uniform, image-based and specular-only pairs (1,500); the mean render PSNR per pattern and variant, and each
variant's mean seconds a material (the reconstruction and its render).

    python research/results/latent-steps/explore.py local/c4/families7 MODEL
"""

from __future__ import annotations

import dataclasses
import sys
import time
import zlib
from collections import defaultdict
from pathlib import Path

import numpy as np

from frenbrdf.io import read_material
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.io.sampling import as_table
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

LATENT = dataclasses.replace(refine_config("latent"), latent_steps=200)  # the budget before this study
VARIANTS = {
    "encoder": refine_config("none"),
    "latent (200 steps)": LATENT,
    "3 starts": dataclasses.replace(LATENT, starts=3),
    "9 starts": dataclasses.replace(LATENT, starts=9),
    "600 steps": dataclasses.replace(LATENT, latent_steps=600),
    "1000 steps": dataclasses.replace(LATENT, latent_steps=1000),
    "2000 steps": dataclasses.replace(LATENT, latent_steps=2000),
    "600 steps, 3 starts": dataclasses.replace(LATENT, latent_steps=600, starts=3),
    "1000 steps from 0.1": dataclasses.replace(LATENT, latent_steps=1000, latent_lr=0.1),
}
CONDITIONS = (("merl-bins", 4000), ("uniform", 1500), ("image-based", 1500), ("specular", 1500))


def main(folder: str, model_spec: str) -> None:
    model, scene = load_model(model_spec), Scene(resolution=128)
    mask = material_mask(scene)
    psnr, seconds = defaultdict(list), defaultdict(list)
    for path in sorted(Path(folder).glob("*.binary"))[::3]:
        truth = read_material(path)
        table, truth_image = as_table(truth), tonemap(render_linear(truth, scene))
        for pattern, count in CONDITIONS:
            rng = np.random.default_rng([0, zlib.crc32(pattern.encode())])
            drawn = pattern_samples(truth, pattern, count, rng, table=table)
            for name, config in VARIANTS.items():
                start = time.perf_counter()
                _, image, _ = refined_reconstruction(model, drawn, scene, config)
                seconds[name].append(time.perf_counter() - start)
                psnr[pattern, name].append(image_metrics(truth_image, image, mask)["psnr"])
        print(path.stem, flush=True)
    for (pattern, name), values in psnr.items():
        print(f"{pattern:12s} {name:22s} {np.mean(values):6.2f} dB")
    for name, values in seconds.items():
        print(f"{name:22s} {np.mean(values):5.2f} s a material")


if __name__ == "__main__":
    main(*sys.argv[1:3])
