"""full-schedule's renders (README.md): measurements read by the fold run that did not train on them, `full` as
shipped and with the candidate schedule, draw 3 as the readings (run with the readings' OMP_NUM_THREADS=1).

    python research/results/full-schedule/look.py WORK FIGURE MATERIAL:FOLD...   (WORK: the runs mf-fF-s0)
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import RefineConfig
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import measurement_row, save_image_grid  # noqa: E402

#: `full` before and after this study's decision.
CONSTANT = RefineConfig(latent_steps=100, weight_steps=1500, weight_lr=3e-3, width=64)
CANDIDATE = dataclasses.replace(CONSTANT, schedule="cosine", weight_lr=1e-2)


def main(work: str, figure: str, readings: list[str]) -> None:
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for reading in readings:
        material, fold = reading.rsplit(":", 1)
        model = load_model(Path(work) / f"mf-f{fold}-s0")
        columns = [("full (constant 3e-3)", model, CONSTANT), ("cosine from 1e-2", model, CANDIDATE)]
        grid.append((f"{material}\nfold {fold}", measurement_row(material, columns, scene, mask, draw=3)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("work")
    parser.add_argument("figure")
    parser.add_argument("readings", nargs="+", metavar="MATERIAL:FOLD")
    args = parser.parse_args()
    main(args.work, args.figure, args.readings)
