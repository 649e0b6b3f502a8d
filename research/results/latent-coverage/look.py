"""Renders for the latent-coverage study (README.md): truth, `latent`, `latent` with coverage weights, for the
families whose PSNR moved most either way through uniform and image-based pairs (1,500), and the six unseen
measurements through uniform pairs; the samples drawn as compare_models.py draws them.

    python research/results/latent-coverage/look.py OUT FAMILIES research/results/latent-coverage/look.png
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

from frenbrdf.io import read_material
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.io.sampling import as_table
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import condition_rng  # noqa: E402
from image_grid import reconstruction_row, save_image_grid  # noqa: E402

BUDGETS = {"latent": refine_config("latent"), "coverage 32": dataclasses.replace(refine_config("latent"), coverage_k=32)}


def changes(rows: list[dict], pattern: str) -> dict[str, float]:
    psnr = {(r["material"], r["budget"]): r["psnr"] for r in rows if r["pattern"] == pattern}
    return {m: psnr[m, "latent@coverage_k=32"] - psnr[m, "latent"] for m, b in psnr if b == "latent"}


def main(out: str, families: str, figure: str) -> None:
    rows = json.loads((Path(out) / "families-devices" / "compare.json").read_text())["rows"]
    cases = []
    for pattern in ("uniform", "image-based"):
        ranked = sorted(changes(rows, pattern).items(), key=lambda item: item[1])
        cases += [(Path(families) / f"{name}.binary", pattern) for name, _ in (ranked[0], ranked[-1])]
    unseen = ("acrylic_felt_green_rgb", "cg_sunflower_rgb", "ilm_l3_37_metallic_rgb", "paper_blue_rgb",
              "paper_white_rgb", "vch_golden_yellow_rgb")
    cases += [(Path("../shared/data/rgl-measured") / f"{name}.bsdf", "uniform") for name in unseen]
    model, scene = load_model("pretrained"), Scene(resolution=128)
    columns = [(name, model, config) for name, config in BUDGETS.items()]
    mask = material_mask(scene)
    grid = []
    for path, pattern in cases:
        truth = read_material(path)
        table = as_table(truth) if path.suffix == ".binary" else None
        drawn = pattern_samples(truth, pattern, 1500, condition_rng(0, pattern), table=table)
        grid.append((f"{path.stem[:22]}\n{pattern}", reconstruction_row(truth, drawn, columns, scene, mask)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:4])
