"""Renders for the latent-native study (README.md): the two readings whose PSNR 1,200 steps moved most down and the
two moved most up, among the 19 measurements (4,000 random bins, each by its fold run) and the families through
in-plane pairs (1,500, the pattern that lost), as truth, the encoder, `latent` at 600 steps and at 1,200.

    python research/results/latent-native/look.py OUT RUNS FAMILIES research/results/latent-native/look.jpg
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from frenbrdf.models.autoencoder import load_model
from frenbrdf.render.renderer import Scene, material_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import budget_config  # noqa: E402
from image_grid import material_row, measurement_row, save_image_grid  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from decide import BASE, CANDIDATE  # noqa: E402

CASES = 2


def largest_changes(rows: list[dict], group: str, pattern: str) -> list[tuple[str, str, float]]:
    """(model, material, 1,200 − 600 steps' PSNR): the :data:`CASES` largest losses, then the largest gains."""
    psnr = {(r["budget"], r["model"], r["material"]): r["psnr"] for r in rows
            if r["group"] == group and r.get("pattern", "merl-bins") == pattern}
    changes = sorted((value - psnr[BASE, model, material], model, material)
                     for (budget, model, material), value in psnr.items() if budget == CANDIDATE)
    return [(model, material, change) for change, model, material in changes[:CASES] + changes[::-1][:CASES]]


def main(out: str, runs: str, families: str, figure: str) -> None:
    scene = Scene(resolution=128)
    mask = material_mask(scene)

    def columns(model):
        return [("encoder", model, budget_config("none")), ("latent, 600", model, budget_config(BASE)),
                ("latent, 1,200", model, budget_config(CANDIDATE))]

    grid = []
    measured = json.loads((Path(out) / "measured" / "compare.json").read_text())["rows"]
    for label, material, change in largest_changes(measured, "measured", "merl-bins"):
        model = load_model(Path(runs) / f"mf-{label.split('/')[-1]}-s0")  # label mf/fF
        grid.append((f"random bins ({change:+.1f} dB)\n{material[:24]}",
                     measurement_row(material, columns(model), scene, mask)))
    shipped = load_model("pretrained")
    devices = json.loads((Path(out) / "families-devices" / "compare.json").read_text())["rows"]
    group = next(r["group"] for r in devices if r["pattern"] == "in-plane")
    for _, material, change in largest_changes(devices, group, "in-plane"):
        grid.append((f"in-plane ({change:+.1f} dB)\n{material[:24]}",
                     material_row(Path(families) / f"{material}.binary", columns(shipped), scene, mask, "in-plane",
                                  1500)))
    save_image_grid(grid, figure)


if __name__ == "__main__":
    main(*sys.argv[1:5])
