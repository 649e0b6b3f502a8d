"""decoder-width's exploration (README.md): `irid_flake_paint2` read by a decoder trained on seven measurements only
(it among them), from its last checkpoint: encoder, `latent` and `full` beside the truth; 4,000 random valid bins,
draw 0.

    python research/results/decoder-width/irid_seven.py CHECKPOINT research/results/decoder-width/irid-seven.jpg
"""

from __future__ import annotations

import sys
from pathlib import Path

from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import measurement_row, save_image_grid  # noqa: E402


def main(checkpoint: str, figure: str) -> None:
    scene = Scene(resolution=128)
    model = load_model(checkpoint)
    columns = [(f"seven {'encoder' if budget == 'none' else budget}", model, refine_config(budget))
               for budget in ("none", "latent", "full")]
    row = measurement_row("irid_flake_paint2_rgb", columns, scene, material_mask(scene))
    save_image_grid([("trained on it\nwith six others", row)], figure)


if __name__ == "__main__":
    main(*sys.argv[1:3])
