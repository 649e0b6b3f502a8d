"""patterns-v12's renders (README.md): the table the encoder reads worst through uniform, image-based and
specular-only pairs (`red-metallic-paint`) and its next worst from specular-only pairs (`yellow-matte-plastic`), truth, then the shipped model's encoder and `latent`
from 1,500 random bins and from 1,500 specular-only and uniform pairs (draw 0, as compare_models.py draws them).

    python research/results/patterns-v12/look.py TABLES research/results/patterns-v12/look.jpg
"""

from __future__ import annotations

import sys
from pathlib import Path

import frenbrdf
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import material_row, save_image_grid  # noqa: E402

MATERIALS = ("red-metallic-paint", "yellow-matte-plastic")
PATTERNS = ("merl-bins", "specular", "uniform")


def main(tables: str, figure: str) -> None:
    model = frenbrdf.Model.pretrained()
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for material in MATERIALS:
        for pattern in PATTERNS:
            columns = [(f"{budget if budget != 'none' else 'encoder'}", model, refine_config(budget))
                       for budget in ("none", "latent")]
            grid.append((f"{material}\n{pattern}", material_row(Path(tables) / f"{material}.binary", columns, scene,
                                                                 mask, pattern, 1500)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:])
