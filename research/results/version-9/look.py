"""Renders for research/results/version-9 (README.md): the held-out tables read worst by version 9's encoder,
through random bins (4,000) and through a device's pattern (1,500, at most one case per table), as truth, version 8
and version 9 from their encoders, and version 9 with `latent` as `frenbrdf reconstruct` runs it for the pattern
(the coverage weights, K = 32, for a device's samples); draw 0, as compare_models.py draws them.

    python research/results/version-9/look.py OUT V8 V9 DATA research/results/version-9/look.jpg

V8 and V9 are packed folders (version 8's: its three files from git, e.g. ``git show
5702e44:python/frenbrdf/models/pretrained/model.pt``).
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

from frenbrdf.io.patterns import DEFAULT as RANDOM_BINS
from frenbrdf.models.autoencoder import load_model
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import budget_config  # noqa: E402
from image_grid import material_row, save_image_grid  # noqa: E402

CASES = {"random bins": 2, "devices": 4}


def worst(rows: list[dict], devices: bool, count: int) -> list[tuple[str, str]]:
    """The (pattern, table) readings with the highest `v9` encoder ΔE at ``count`` samples, through random bins or
    through the devices' patterns, at most one per table."""
    delta_e = defaultdict(float)
    for r in rows:
        if r["model"] == "v9" and r["budget"] == "none" and r["count"] == count and \
                (r["pattern"] != RANDOM_BINS) == devices:
            delta_e[(r["pattern"], r["material"])] = r["delta_e"]
    cases, seen = [], set()
    for pattern, material in sorted(delta_e, key=lambda key: -delta_e[key]):
        if material not in seen:
            cases.append((pattern, material))
            seen.add(material)
    return cases[:CASES["devices" if devices else "random bins"]]


def main(out: str, v8: str, v9: str, data: str, figure: str) -> None:
    tables = json.loads((Path(out) / "tables" / "compare.json").read_text())["rows"]
    patterns = [row for half in sorted(Path(out).glob("patterns-*/compare.json"))
                for row in json.loads(half.read_text())["rows"]]
    v8, v9 = load_model(v8), load_model(v9)
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for (pattern, material), count in [*((case, 4000) for case in worst(tables, False, 4000)),
                                       *((case, 1500) for case in worst(patterns, True, 1500))]:
        latent = "latent" if pattern == RANDOM_BINS else "latent@coverage_k=32"
        columns = [("v8 encoder", v8, budget_config("none")), ("v9 encoder", v9, budget_config("none")),
                   (f"v9 {latent.split('@')[0]}", v9, budget_config(latent))]
        row = material_row(Path(data) / f"{material}.binary", columns, scene, mask, pattern, count)
        grid.append((f"{pattern} × {count}\n{material[:24]}", row))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:6])
