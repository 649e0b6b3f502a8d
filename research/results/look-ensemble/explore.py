"""Exploration only (research/results/look-ensemble): version 11's encoders' z, then second-look's three looks (s1, s2,
s3 in local/sl/judge), each taken twice alone, and the three with their answers averaged at each look, once and
twice; encoder alone, 1,500 pairs, draw 0. Prints each pattern's mean PSNR by variant.

    python research/results/look-ensemble/explore.py OUT.json MATERIALS...
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from pattern_readings import readings  # noqa: E402
from second_look import PATTERNS, first_look, look_samples, trained_look  # noqa: E402

from frenbrdf import Model  # noqa: E402
from frenbrdf.render import Scene, material_mask, render_linear, tonemap  # noqa: E402

RUNS = Path("local/sl/judge")


def averaged(looks, z: torch.Tensor, samples: tuple, decoder) -> torch.Tensor:
    """The looks' answers from ``z`` (``samples``: coords, mapped values, cos θ_i), averaged."""
    return torch.stack([look(*samples, z, decoder) for look in looks]).mean(0)


def main(out: Path, materials: list[Path]) -> int:
    model = Model.pretrained()
    decoder = model.network.decoder
    looks = [trained_look(RUNS / run, model.config.encoder.latent) for run in ("s1", "s2", "s3")]
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    rows = []
    for reading in readings(materials, PATTERNS, [0], 1500, scene, mask):
        z1 = torch.from_numpy(first_look(model, reading.values, reading.directions))[None]
        samples = look_samples(model, reading)
        with torch.no_grad():
            variants = {f"{run} ×2": averaged([look], averaged([look], z1, samples, decoder), samples, decoder)
                        for run, look in zip(("s1", "s2", "s3"), looks, strict=True)}
            variants["mean ×1"] = averaged(looks, z1, samples, decoder)
            variants["mean ×2"] = averaged(looks, variants["mean ×1"], samples, decoder)
        for name, z in variants.items():
            metrics = reading.metrics(tonemap(render_linear(model.decode(z[0].numpy())[0], scene)), mask)
            rows.append({"material": reading.material, "pattern": reading.pattern, "variant": name,
                         "psnr": metrics["psnr"], "delta_e": metrics["delta_e"]})
    out.write_text(json.dumps(rows))
    names = list(dict.fromkeys(row["variant"] for row in rows))
    for pattern in PATTERNS:
        means = [np.mean([r["psnr"] for r in rows if r["pattern"] == pattern and r["variant"] == n]) for n in names]
        print(pattern, " ".join(f"{name} {mean:.2f}" for name, mean in zip(names, means, strict=True)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1]), [Path(p) for p in sys.argv[2:]]))
