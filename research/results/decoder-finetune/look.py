"""decoder-finetune's renders (README.md): measurements read by a fold's base run and its fine-tuned copy (with
``--arm refit`` the copy with its encoder trained again, with ``--arm joint`` the copy fitted with its encoder, with ``--arm anchor`` the fit that kept its encoder, with ``--arm augment`` that fit on augmented materials), each
budget's reconstruction beside the truth; 4,000 random valid bins, draw 0 (``--draw``: another).

    python research/results/decoder-finetune/look.py WORK FT FIGURE MATERIAL:FOLD... [--arm ft] [--budgets latent full]
        [--draw 0] [--base mfw512]
    (WORK: the base runs BASE-fF-s0, BASE mf for the fifth amendment's; FT: the runs ARM-fF; FOLD: the run that
    reads MATERIAL)
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

LABELS = {"ft": "fine-tuned", "refit": "refit", "joint": "joint fit", "anchor": "anchored fit", "augment": "augmented fit"}


def main(work: str, ft: str, figure: str, readings: list[str], arm: str, budgets: list[str], draw: int = 0,
         base: str = "mfw512") -> None:
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for reading in readings:
        material, fold = reading.rsplit(":", 1)
        models = (("base", load_model(Path(work) / f"{base}-f{fold}-s0")),
                  (LABELS[arm], load_model(Path(ft) / f"{arm}-f{fold}")))
        columns = [(f"{label} {'encoder' if budget == 'none' else budget}", model, refine_config(budget))
                   for label, model in models for budget in budgets]
        grid.append((f"{material}\nfold {fold}", measurement_row(material, columns, scene, mask, draw=draw)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("work")
    parser.add_argument("ft")
    parser.add_argument("figure")
    parser.add_argument("readings", nargs="+", metavar="MATERIAL:FOLD")
    parser.add_argument("--arm", choices=tuple(LABELS), default="ft")
    parser.add_argument("--budgets", nargs="+", choices=("none", "latent", "full"), default=["latent", "full"])
    parser.add_argument("--draw", type=int, default=0, help="which draw of random bins (run.sh's DRAW)")
    parser.add_argument("--base", default="mfw512", help="the base runs' arm (run.sh's BASE)")
    args = parser.parse_args()
    main(args.work, args.ft, args.figure, args.readings, args.arm, args.budgets, args.draw, args.base)
