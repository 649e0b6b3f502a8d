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
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import measurement_row  # noqa: E402

FOLDS = json.loads((Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json").read_text())
MATERIALS = ("vch_dragon_eye_red_rgb", "cg_sunflower_rgb")


def centre(image: np.ndarray) -> np.ndarray:
    """The middle third of the image, enlarged 3× (nearest pixel, so that a one-pixel line stays one line)."""
    n = image.shape[0] // 3
    return np.repeat(np.repeat(image[n:2 * n, n:2 * n], 3, axis=0), 3, axis=1)


def raised(image: np.ndarray) -> np.ndarray:
    """The image's contrast raised 3× about its mean."""
    return image.mean() + 3 * (image - image.mean())


def main(work: str, figure: str) -> None:
    scene = Scene(resolution=384)
    shipped = frenbrdf.Model.pretrained()
    rows = []
    for material in MATERIALS:
        fold = next(k for k, names in enumerate(FOLDS["folds"]) if material in names)
        columns = [(title, model, refine_config("latent"))
                   for title, model in (("shipped", shipped), ("mftie", load_model(Path(work) / f"mftie-f{fold}-s0")))]
        rows.append([centre(image) for _, image in measurement_row(material, columns, scene, material_mask(scene))])
    path = Path(figure)
    plt.imsave(path, np.clip(np.concatenate([np.concatenate(row, axis=1) for row in rows]), 0, 1))
    plt.imsave(path.with_name(f"{path.stem}-contrast{path.suffix}"),
               np.clip(np.concatenate([np.concatenate([raised(crop) for crop in row], axis=1) for row in rows]), 0, 1))


if __name__ == "__main__":
    main(*sys.argv[1:])
