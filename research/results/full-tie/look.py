"""The full-tie study's renders: truth, `full` and `full@tie=0.1` for the measurements and tables that lost most,
and the measurement whose seam shrank most, each render also zoomed 3× about its centre (where the seams meet).

    python research/results/full-tie/look.py OUT TABLES research/results/full-tie/look.jpg
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import budget_config  # noqa: E402
from image_grid import material_row, save_image_grid  # noqa: E402

from frenbrdf.models.autoencoder import load_model  # noqa: E402
from frenbrdf.render.renderer import Scene, material_mask  # noqa: E402

MEASURED = Path("../shared/data/rgl-measured")


def zoomed(image: np.ndarray, factor: int = 3) -> np.ndarray:
    """The centre 1/factor of ``image``, enlarged back to its size."""
    size = image.shape[0] // factor
    start = (image.shape[0] - size) // 2
    return np.repeat(np.repeat(image[start:start + size, start:start + size], factor, 0), factor, 1)


def main() -> None:
    out, tables, path = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
    worst = {}
    for name in ("measured", "tables"):
        rows = json.loads((out / name / "compare.json").read_text())["rows"]
        by = {(row["material"], row["budget"]): row["psnr"] for row in rows}
        worst[name] = min({row["material"] for row in rows}, key=lambda m: by[m, "full@tie=0.1"] - by[m, "full"])
    seams = json.loads((out / "seam.json").read_text())["materials"]
    shrank = max(seams, key=lambda m: seams[m]["full"]["p90"] - seams[m]["full@tie=0.1"]["p90"])
    model, scene = load_model("pretrained"), Scene(resolution=256)
    mask = material_mask(scene)
    columns = [("full", model, budget_config("full")), ("full@tie=0.1", model, budget_config("full@tie=0.1"))]
    grid = []
    for label, material in ((f"{worst['measured']} (lost most)", MEASURED / f"{worst['measured']}.bsdf"),
                            (f"{worst['tables']} (lost most)", tables / f"{worst['tables']}.binary"),
                            (f"{shrank} (seam shrank most)", MEASURED / f"{shrank}.bsdf")):
        row = material_row(material, columns, scene, mask)
        grid.append((label, row + [(f"{title.splitlines()[0]}, centre ×3", zoomed(image)) for title, image in row]))
    save_image_grid(grid, path)


if __name__ == "__main__":
    main()
