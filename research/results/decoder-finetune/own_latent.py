"""decoder-finetune's diagnosis (README.md): measurements a fitted decoder trained on, rendered from the latent the
fit gave each (``latents.npz``) and with `latent` from 4,000 random valid bins (draw 0), beside the truth.

    python research/results/decoder-finetune/own_latent.py FITTED FIGURE MATERIAL...
    (FITTED: a `frenbrdf fit-decoder` output whose run trained on each MATERIAL)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from frenbrdf.io import read_material
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import condition_rng  # noqa: E402
from image_grid import save_image_grid  # noqa: E402

MEASURED = Path("../shared/data/rgl-measured")


def main(fitted: str, figure: str, materials: list[str]) -> None:
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    model = load_model(fitted)
    latents = np.load(Path(fitted) / "latents.npz")
    names = list(latents["names"])
    rows = []
    for material in materials:
        truth = read_material(MEASURED / f"{material}.bsdf")
        truth_image = tonemap(render_linear(truth, scene))
        own = tonemap(render_linear(model.decode(latents["latents"][names.index(material)]), scene))
        drawn = pattern_samples(truth, "merl-bins", 4000, condition_rng(0, "merl-bins"))
        _, refined, _ = refined_reconstruction(model, drawn, scene, refine_config("latent"))
        row = [("truth", truth_image)]
        for title, image in (("its latent from the fit", own), ("latent", refined)):
            metrics = image_metrics(truth_image, image, mask)
            row.append((f"{title}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.1f}", image))
            print(material, title, f"{metrics['psnr']:.2f} dB, ΔE {metrics['delta_e']:.2f}")
        rows.append((material, row))
    save_image_grid(rows, figure)


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
