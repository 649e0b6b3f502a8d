"""decoder-finetune's renders (README.md): measurements read by a fold's base run and its fine-tuned copy, `latent`
and `full` from each, beside the truth; 4,000 random valid bins, draw 0.

    python research/results/decoder-finetune/look.py WORK FT FIGURE MATERIAL:FOLD...
    (WORK: the base runs mfw512-fF-s0; FT: the fine-tuned ft-fF; FOLD: the run that reads MATERIAL)
"""

from __future__ import annotations

import sys
from pathlib import Path

from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import measurement_row, save_image_grid  # noqa: E402


def main(work: str, ft: str, figure: str, readings: list[str]) -> None:
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for reading in readings:
        material, fold = reading.rsplit(":", 1)
        base, tuned = load_model(Path(work) / f"mfw512-f{fold}-s0"), load_model(Path(ft) / f"ft-f{fold}")
        columns = [(f"{label} {budget}", model, refine_config(budget))
                   for label, model in (("base", base), ("fine-tuned", tuned)) for budget in ("latent", "full")]
        grid.append((f"{material}\nfold {fold}", measurement_row(material, columns, scene, mask)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:])
