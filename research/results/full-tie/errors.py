"""Where `full@tie=0.1` loses against `full`: each one's error against the truth and their difference, for the
measurement and the table that lost most (full-tie's README).

    python research/results/full-tie/errors.py TABLES research/results/full-tie/errors.jpg
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import budget_config, condition_rng  # noqa: E402

from frenbrdf.io import read_material  # noqa: E402
from frenbrdf.io.patterns import pattern_samples  # noqa: E402
from frenbrdf.models.autoencoder import load_model  # noqa: E402
from frenbrdf.render.renderer import Scene, render_linear, tonemap  # noqa: E402
from frenbrdf.render.scoring import refined_reconstruction  # noqa: E402

BUDGETS = ("full", "full@tie=0.1")


def main() -> None:
    tables, path = Path(sys.argv[1]), Path(sys.argv[2])
    model, scene = load_model("pretrained"), Scene(resolution=256)
    materials = [Path("../shared/data/rgl-measured/acrylic_felt_white_rgb.bsdf"), tables / "nylon.binary"]
    figure, axes = plt.subplots(len(materials), 4, figsize=(12, 6.2), squeeze=False)
    for row, material in zip(axes, materials, strict=True):
        truth = read_material(material)
        drawn = pattern_samples(truth, "merl-bins", 4000, condition_rng(0, "merl-bins"))
        shown = tonemap(render_linear(truth, scene))
        images = {budget: refined_reconstruction(model, drawn, scene, budget_config(budget))[1] for budget in BUDGETS}
        row[0].imshow(np.clip(shown, 0, 1))
        row[0].set_title(material.name)
        for axis, budget in zip(row[1:3], BUDGETS, strict=True):
            axis.imshow(np.abs(images[budget] - shown).mean(-1), vmin=0, vmax=0.03, cmap="magma")
            axis.set_title(f"|{budget} − truth| (display)")
        difference = (images[BUDGETS[1]] - images[BUDGETS[0]]).mean(-1)
        row[3].imshow(np.clip(difference * 20 + 0.5, 0, 1), cmap="coolwarm")
        row[3].set_title("tied − full, ×20")
    for axis in axes.flat:
        axis.set_xticks([]), axis.set_yticks([])
    figure.tight_layout()
    figure.savefig(path, dpi=70)


if __name__ == "__main__":
    main()
