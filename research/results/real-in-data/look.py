"""Renders for research/results/real-in-data (README.md): the worst measurement of each kind by the `mf` encoder,
as truth, then `v8`'s first run and the `mf` run of the material's own fold (which did not train on it), each from
its encoder and with `latent`; 4,000 random valid bins, draw 0, as compare_models.py draws them.

    python research/results/real-in-data/look.py OUT V8_RUNS MF_RUNS research/results/real-in-data/look.jpg
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


def worst_of_each_kind(rows: list[dict]) -> list[tuple[str, str]]:
    """(kind, material) with the lowest encoder PSNR of the `mf` run that judged it, per kind."""
    psnr = {r["material"]: r["psnr"] for r in rows if r["model"].startswith("mf/") and r["budget"] == "none"}
    return [(kind, min(names, key=psnr.__getitem__)) for kind, names in FOLDS["kinds"].items()]


def main(out: str, v8_runs: str, mf_runs: str, figure: str) -> None:
    rows = json.loads((Path(out) / "measured" / "compare.json").read_text())["rows"]
    v8 = load_model(Path(v8_runs) / "v8-s0")
    mf = [load_model(Path(mf_runs) / f"mf-f{fold}-s0") for fold in range(len(FOLDS["folds"]))]
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for kind, material in worst_of_each_kind(rows):
        fold = next(k for k, names in enumerate(FOLDS["folds"]) if material in names)
        columns = [(f"{name} {'encoder' if budget == 'none' else 'latent'}", model, refine_config(budget))
                   for budget in ("none", "latent") for name, model in (("v8", v8), ("mf", mf[fold]))]
        grid.append((f"{kind}\n{material[:24]}", measurement_row(material, columns, scene, mask)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:5])
