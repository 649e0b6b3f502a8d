"""fold-tie's close look at the seam (README.md): two of the four measurements with the largest steps in the shipped
model (research/results/seam), each rendered at 384² from its `latent` reconstruction (4,000 random valid bins,
draw 0), the centre third enlarged 3×, as truth, the shipped model (trained on all 19) and `mftie`'s run of the
measurement's own fold (which did not train on it): one row a material, the three columns in that order, at full
size (a one-pixel line must not be scaled away); beside it the same with each crop's contrast raised 3× about its
mean (FIGURE's name with ``-contrast``).

    python research/results/fold-tie/look_seam.py WORK research/results/fold-tie/seam.png   (WORK: local/rid)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import frenbrdf
from frenbrdf.io import read_material
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, render_linear, tonemap
from frenbrdf.render.scoring import refined_reconstruction

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import condition_rng  # noqa: E402

FOLDS = json.loads((Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json").read_text())
MATERIALS = ("vch_dragon_eye_red_rgb", "cg_sunflower_rgb")
MEASURED = Path("../shared/data/rgl-measured")


def centre(image: np.ndarray) -> np.ndarray:
    """The middle third of the image, enlarged 3× (nearest pixel, so that a one-pixel line stays one line)."""
    n = image.shape[0] // 3
    return np.repeat(np.repeat(image[n:2 * n, n:2 * n], 3, axis=0), 3, axis=1)


def main(work: str, figure: str) -> None:
    from frenbrdf.io.patterns import pattern_samples

    scene = Scene(resolution=384)
    shipped = frenbrdf.Model.pretrained()
    grid = []
    for material in MATERIALS:
        fold = next(k for k, names in enumerate(FOLDS["folds"]) if material in names)
        truth = read_material(MEASURED / f"{material}.bsdf")
        drawn = pattern_samples(truth, "merl-bins", 4000, condition_rng(0, "merl-bins"))
        images = [centre(tonemap(render_linear(truth, scene)))]
        for model in (shipped, load_model(Path(work) / f"mftie-f{fold}-s0")):
            _, image, _ = refined_reconstruction(model, drawn, scene, refine_config("latent"))
            images.append(centre(image))
        grid.append(np.concatenate(images, axis=1))
    mosaic = np.concatenate(grid, axis=0)
    plt.imsave(figure, np.clip(mosaic, 0, 1))
    crops = mosaic.reshape(len(MATERIALS), 128 * 3, 3, 128 * 3, 3).transpose(0, 2, 1, 3, 4)
    mean = crops.mean(axis=(2, 3, 4), keepdims=True)
    raised = (mean + 3 * (crops - mean)).transpose(0, 2, 1, 3, 4).reshape(mosaic.shape)
    path = Path(figure)
    plt.imsave(path.with_name(f"{path.stem}-contrast{path.suffix}"), np.clip(raised, 0, 1))


if __name__ == "__main__":
    main(*sys.argv[1:])
