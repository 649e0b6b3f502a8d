"""Renders for research/results/raw-measured (README.md): the three measurements whose encoder reading `mfraw` lost
most against the baseline (decision.json's per-measurement changes), as truth, then `mfraw`'s run of the
measurement's own fold from its encoder and with `latent`; 4,000 random valid bins, draw 0, as compare_models.py
draws them.

    python research/results/raw-measured/look_losses.py OUT WORK research/results/raw-measured/losses.jpg
    (OUT: decide.py's folder; WORK: the folder of the runs, local/raw)
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


def main(out: str, work: str, figure: str) -> None:
    changes = json.loads((Path(out) / "decision.json").read_text())["reported"]["per measurement, PSNR change"]["none"]
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for material in sorted(changes, key=changes.__getitem__)[:3]:
        fold = next(k for k, names in enumerate(FOLDS["folds"]) if material in names)
        model = load_model(Path(work) / f"mfraw-f{fold}-s0")
        columns = [(f"mfraw {'encoder' if budget == 'none' else 'latent'}", model, refine_config(budget))
                   for budget in ("none", "latent")]
        grid.append((f"{material[:24]}\n{changes[material]:+.2f} dB", measurement_row(material, columns, scene, mask)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("work")
    parser.add_argument("figure")
    args = parser.parse_args()
    main(args.out, args.work, args.figure)
