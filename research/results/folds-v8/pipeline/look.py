"""Renders for the pipeline amendment (../README.md): the worst readings through a device by the `pipe` candidates'
encoder (mean ΔE over the three), as truth, `v8`'s first run from its encoder, `pipe`'s first candidate from its
encoder, and with `latent` as `frenbrdf reconstruct` runs it for a device's samples (the coverage weights, K = 32);
1,500 samples, draw 0, as compare_models.py draws them.

    python research/results/folds-v8/pipeline/look.py OUT RUNS PIPE research/results/folds-v8/pipeline/look.jpg
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from frenbrdf.io import read_material
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "studies"))
from compare_models import budget_config, condition_rng  # noqa: E402
from image_grid import reconstruction_row, save_image_grid  # noqa: E402

CASES = 5
COUNT = 1500


def worst_readings(rows: list[dict]) -> list[tuple[str, str]]:
    """The (pattern, material) pairs with the highest mean encoder ΔE over the `pipe` candidates, at most one per
    material, random bins left out."""
    delta_e = defaultdict(list)
    for r in rows:
        if r["model"].startswith("pipe/") and r["budget"] == "none" and r["pattern"] != "merl-bins":
            delta_e[(r["pattern"], r["material"])].append(r["delta_e"])
    cases, seen = [], set()
    for pattern, material in sorted(delta_e, key=lambda key: -np.mean(delta_e[key])):
        if material not in seen:
            cases.append((pattern, material))
            seen.add(material)
    return cases[:CASES]


def main(out: str, runs: str, pipe: str, figure: str) -> None:
    rows = json.loads((Path(out) / "patterns-pipe" / "compare.json").read_text())["rows"]
    pipe = load_model(Path(pipe) / "cand-s0")
    columns = [("v8 encoder", load_model(Path(runs) / "v8-s0"), budget_config("none")),
               ("pipe encoder", pipe, budget_config("none")),
               ("pipe latent, coverage", pipe, budget_config("latent@coverage_k=32"))]
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for pattern, material in worst_readings(rows):
        truth = read_material(Path("../shared/data/rgl-measured") / f"{material}.bsdf")
        drawn = pattern_samples(truth, pattern, COUNT, condition_rng(0, pattern))
        grid.append((f"{pattern}\n{material[:24]}", reconstruction_row(truth, drawn, columns, scene, mask)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:5])
