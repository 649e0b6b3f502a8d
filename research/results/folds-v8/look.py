"""Renders for research/results/folds-v8 (README.md): the worst measurement of each kind by the `v8` arm's encoder
(mean over its runs), as truth, `v4`'s first run from its encoder, and `v8`'s first run from its encoder, `latent`
and `full`; 4,000 random valid bins, draw 0, as compare_models.py draws them.

    python research/results/folds-v8/look.py OUT RUNS research/results/folds-v8/look.jpg
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import measurement_row, save_image_grid  # noqa: E402

KINDS = json.loads((Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json").read_text())
COLUMNS = (("v4-s0", "none"), ("v8-s0", "none"), ("v8-s0", "latent"), ("v8-s0", "full"))


def worst_of_each_kind(rows: list[dict]) -> list[tuple[str, str]]:
    """(kind, material) with the lowest mean encoder PSNR over the `v8` runs, per kind."""
    mine = [r for r in rows if r["model"].startswith("v8/") and r["budget"] == "none"]
    psnr = {m: np.mean([r["psnr"] for r in mine if r["material"] == m]) for m in {r["material"] for r in mine}}
    return [(kind, min(names, key=psnr.__getitem__)) for kind, names in KINDS["kinds"].items()]


def main(out: str, runs: str, figure: str) -> None:
    rows = json.loads((Path(out) / "measured" / "compare.json").read_text())["rows"]
    cases = worst_of_each_kind(rows)
    models = {name: load_model(Path(runs) / name) for name in {name for name, _ in COLUMNS}}
    columns = [(f"{name.split('-')[0]} " + ("encoder" if budget == "none" else f"{budget}, {{seconds:.1f}} s"),
                models[name], refine_config(budget)) for name, budget in COLUMNS]
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for kind, material in cases:
        grid.append((f"{kind}\n{material[:24]}", measurement_row(material, columns, scene, mask)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:4])
