"""latent-size's addendum (README.md): `irid_flake_paint2` read by runs that trained on it (real-in-data's `mf`
seed-0 runs of folds 0 and 2), encoder, `latent` and `full`, beside the truth; 4,000 random valid bins, draw 0.

    python research/results/latent-size/irid_trained.py WORK research/results/latent-size/irid-trained.jpg [--arm mf]
    (WORK: the folder of the runs, local/rid; research/results/decoder-width reads its `mfw512` runs with --arm)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import measurement_row, save_image_grid  # noqa: E402

MATERIAL = "irid_flake_paint2_rgb"
FOLDS_TRAINED_ON_IT = (0, 2)


def save_irid_rows(models: dict[str, str | Path], figure: str) -> None:
    """One row per model (label → run folder or checkpoint): truth, encoder, `latent`, `full`."""
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for label, path in models.items():
        model = load_model(path)
        columns = [(f"{label} {'encoder' if budget == 'none' else budget}", model, refine_config(budget))
                   for budget in ("none", "latent", "full")]
        grid.append((f"trained on it\n{label}", measurement_row(MATERIAL, columns, scene, mask)))
    save_image_grid(grid, figure)


def main(work: str, figure: str, arm: str = "mf") -> None:
    runs = [f"{arm}-f{fold}-s0" for fold in FOLDS_TRAINED_ON_IT]
    save_irid_rows({run: Path(work) / run for run in runs}, figure)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("work")
    parser.add_argument("figure")
    parser.add_argument("--arm", default="mf")
    args = parser.parse_args()
    main(args.work, args.figure, args.arm)
