"""Exploration only (research/results/repeated-look): the package model's look taken 0–8 times, z_{k+1} = look(z_k),
encoder alone, 1,500 pairs, draw 0, with the samples' loss under each z; prints each pattern's mean PSNR / ΔE and the worst material's PSNR by looks.

    python research/results/repeated-look/explore.py OUT.json MATERIALS...
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from pattern_readings import readings  # noqa: E402
from second_look import PATTERNS, first_look, look_samples  # noqa: E402

from frenbrdf import Model  # noqa: E402
from frenbrdf.models.losses import samples_loss  # noqa: E402
from frenbrdf.render import Scene, material_mask, render_linear, tonemap  # noqa: E402

MOST_LOOKS = 8


def main(out: Path, materials: list[Path]) -> int:
    model = Model.pretrained()
    look = model.network.second_look
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    rows = []
    for reading in readings(materials, PATTERNS, [0], 1500, scene, mask):
        z = torch.from_numpy(first_look(model, reading.values, reading.directions))[None]
        coords, mapped, cos_in = look_samples(model, reading)
        for k in range(MOST_LOOKS + 1):
            metrics = reading.metrics(tonemap(render_linear(model.decode(z[0].numpy())[0], scene)), mask)
            with torch.no_grad():
                loss = samples_loss(model.network.decoder(z), coords, mapped, cos_in)
            rows.append({"material": reading.material, "pattern": reading.pattern, "k": k, "psnr": metrics["psnr"],
                         "de": metrics["delta_e"], "loss": loss})
            with torch.no_grad():
                z = look(coords, mapped, cos_in, z, model.network.decoder)
    out.write_text(json.dumps(rows))
    for pattern in PATTERNS:
        cells = []
        for k in range(MOST_LOOKS + 1):
            here = [r for r in rows if r["pattern"] == pattern and r["k"] == k]
            psnr = [r["psnr"] for r in here]
            cells.append(f"{k}: {np.mean(psnr):.2f}/{np.mean([r['de'] for r in here]):.2f} min {np.min(psnr):.1f}")
        print(" | ".join([pattern, *cells]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1]), [Path(p) for p in sys.argv[2:]]))
