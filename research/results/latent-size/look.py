"""Renders for research/results/latent-size (README.md): the measurement of each kind that `mf128` reads worst
with `latent`, as truth, then `mf`'s seed-0 run and the `mf128` run of the material's own fold (neither trained on
it), each from its encoder and with `latent`; 4,000 random valid bins, draw 0, as compare_models.py draws them.

    python research/results/latent-size/look.py OUT WORK research/results/latent-size/look.jpg
    (OUT: decide.py's folder; WORK: the folder of the runs, local/rid)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import measurement_row, save_image_grid  # noqa: E402

FOLDS = json.loads((Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json").read_text())


def main(out: str, work: str, figure: str) -> None:
    rows = [row for path in sorted(Path(out).glob("mf128-f*/compare.json"))
            for row in json.loads(path.read_text())["rows"]]
    psnr = {r["material"]: r["psnr"] for r in rows if r["budget"] == "latent"}
    arms = {arm: [load_model(Path(work) / f"{arm}-f{fold}-s0") for fold in range(len(FOLDS["folds"]))]
            for arm in ("mf", "mf128")}
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for kind, names in FOLDS["kinds"].items():
        material = min(names, key=psnr.__getitem__)
        fold = next(k for k, fold_names in enumerate(FOLDS["folds"]) if material in fold_names)
        columns = [(f"{arm} {'encoder' if budget == 'none' else 'latent'}", models[fold], refine_config(budget))
                   for budget in ("none", "latent") for arm, models in arms.items()]
        grid.append((f"{kind}\n{material[:24]}", measurement_row(material, columns, scene, mask)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:4])
