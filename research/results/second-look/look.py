"""second-look's renders (README.md): materials through a pattern, the truth beside version 9's first look and a
run's second look, each titled with its PSNR / ΔE; 1,500 samples, draw 0 (the readings' samples).

    python research/results/second-look/look.py RUN FIGURE MATERIAL:PATTERN... [--count 1500] [--draw 0]
    (MATERIAL: a file of a MERL table or a measurement)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

from frenbrdf import Model
from frenbrdf.render import Scene, material_mask, render_linear, tonemap

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import save_image_grid  # noqa: E402
from pattern_readings import readings  # noqa: E402
from second_look import first_look, look_samples, trained_look  # noqa: E402

PATTERNS = ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "specular")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("figure", type=Path)
    parser.add_argument("readings", nargs="+", metavar="MATERIAL:PATTERN")
    parser.add_argument("--count", type=int, default=1500)
    parser.add_argument("--draw", type=int, default=0)
    args = parser.parse_args(argv)
    model = Model.pretrained()
    look = trained_look(args.run, model.config.encoder.latent)
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for spec in args.readings:
        path, pattern = spec.rsplit(":", 1)
        # The pattern's place in the readings' order seeds its samples: the same samples the readings scored.
        reading = next(r for r in readings([Path(path)], PATTERNS, [args.draw], args.count, scene, mask)
                       if r.pattern == pattern)
        z1 = first_look(model, reading.values, reading.directions)
        coords, mapped, cos_in = look_samples(model, reading)
        with torch.no_grad():
            z2 = look(coords, mapped, cos_in, torch.from_numpy(z1)[None], model.network.decoder)[0].numpy()
        images = [("truth", reading.truth_image)]
        for label, z in (("first look", z1), ("second look", z2)):
            image = tonemap(render_linear(model.decode(z)[0], scene))
            metrics = reading.metrics(image, mask)
            images.append((f"{label}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.2f}", image))
        grid.append((f"{reading.material}\n{pattern}", images))
    save_image_grid(grid, args.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
