"""Renders for the latent-anchor study (README.md): the readings of the 19 measurements whose PSNR the anchor moved
most, down and up (the first fold candidate's reading; three each, at most one per measurement), as truth, the
encoder, `latent` with coverage weights, and the same with the anchor; 1,500 samples, draw 0, as compare_models.py
draws them.

    python research/results/latent-anchor/look.py OUT local/fv8/pipe research/results/latent-anchor/look.jpg
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.models.autoencoder import load_model
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import budget_config  # noqa: E402
from image_grid import measurement_row, save_image_grid  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from decide import BASE, CANDIDATE  # noqa: E402

CASES = 3
COUNT = 1500


def largest_changes(rows: list[dict]) -> list[tuple[str, str, float]]:
    """(pattern, material, anchor − without PSNR) of the first candidate: the largest losses, then the largest gains,
    :data:`CASES` each, at most one per measurement in each."""
    psnr = {(r["budget"], r["pattern"], r["material"]): r["psnr"] for r in rows
            if r["model"] == "pipe/s0" and r["group"] == "measured"}
    changes = sorted((value - psnr[BASE, pattern, material], pattern, material)
                     for (budget, pattern, material), value in psnr.items() if budget == CANDIDATE)
    chosen = []
    for ordered in (changes, changes[::-1]):
        seen: set[str] = set()
        for change, pattern, material in ordered:
            if material not in seen and len(seen) < CASES:
                chosen.append((pattern, material, change))
                seen.add(material)
    return chosen


def main(out: str, pipe: str, figure: str) -> None:
    rows = json.loads((Path(out) / "measured" / "compare.json").read_text())["rows"]
    model = load_model(Path(pipe) / "cand-s0")
    columns = [("encoder", model, budget_config("none")), ("latent, coverage", model, budget_config(BASE)),
               ("with the anchor", model, budget_config(CANDIDATE))]
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for pattern, material, change in largest_changes(rows):
        grid.append((f"{pattern} ({change:+.1f} dB)\n{material[:24]}",
                     measurement_row(material, columns, scene, mask, pattern, COUNT)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:4])
