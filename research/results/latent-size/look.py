"""Renders for research/results/latent-size (README.md): the measurement of each kind that ARM (`mf128`) reads
worst with `latent`, as truth, then `mf`'s seed-0 run and the ARM run of the material's own fold (neither trained on
it), each from its encoder and with `latent`; 4,000 random valid bins, draw 0, as compare_models.py draws them.
Where WORK lacks `mf`'s runs (they were trained on another machine) the figure shows ARM's alone. With
``--materials``, those measurements instead, labelled by name (research/results/raw-measured's losses.jpg).

    python research/results/latent-size/look.py OUT WORK research/results/latent-size/look.jpg [--arm mf128]
        [--materials NAME ...]
    (OUT: decide.py's folder; WORK: the folder of the runs, local/rid)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import measurement_row, save_image_grid  # noqa: E402

FOLDS = json.loads((Path(__file__).resolve().parents[2] / "studies" / "measured_folds" / "folds.json").read_text())


def main(out: str, work: str, figure: str, arm: str = "mf128", materials: list[str] | None = None) -> None:
    rows = [row for path in sorted(Path(out).glob(f"{arm}-f*/compare.json"))
            for row in json.loads(path.read_text())["rows"]]
    psnr = {r["material"]: r["psnr"] for r in rows if r["budget"] == "latent"}
    folds = range(len(FOLDS["folds"]))
    arms = {a: [load_model(Path(work) / f"{a}-f{fold}-s0") for fold in folds]
            for a in ("mf", arm) if all((Path(work) / f"{a}-f{fold}-s0").is_dir() for fold in folds)}
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    worst = {kind: min(names, key=psnr.__getitem__) for kind, names in FOLDS["kinds"].items()}
    labelled = ([(material, material[:24]) for material in materials] if materials else
                [(material, f"{kind}\n{material[:24]}") for kind, material in worst.items()])
    for material, label in labelled:
        fold = next(k for k, fold_names in enumerate(FOLDS["folds"]) if material in fold_names)
        columns = [(f"{a} {'encoder' if budget == 'none' else 'latent'}", models[fold], refine_config(budget))
                   for budget in ("none", "latent") for a, models in arms.items()]
        grid.append((label, measurement_row(material, columns, scene, mask)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("work")
    parser.add_argument("figure")
    parser.add_argument("--arm", default="mf128")
    parser.add_argument("--materials", nargs="+", help="these measurements instead of each kind's worst")
    args = parser.parse_args()
    main(args.out, args.work, args.figure, args.arm, args.materials)
