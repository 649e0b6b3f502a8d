"""repeated-look's renders (README.md): materials through a pattern, the truth beside the package model's reading
with one look and with two (or the looks ``--models`` names: ``STEPS`` or ``STEPS:CHOICE``, as look-choice's
renders), each titled with its PSNR / ΔE; 1,500 samples, draw 0 (the readings' samples).

    python research/results/repeated-look/look.py FIGURE MATERIAL:PATTERN... [--count 1500] [--draw 0]
        [--models 1 2]
    (MATERIAL: a file of a MERL table or a measurement)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from frenbrdf import Model
from frenbrdf.render import Scene, material_mask, render_linear, tonemap

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import save_image_grid  # noqa: E402
from pattern_readings import readings  # noqa: E402
from repeated_look import with_steps  # noqa: E402
from second_look import PATTERNS  # noqa: E402


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("figure", type=Path)
    parser.add_argument("readings", nargs="+", metavar="MATERIAL:PATTERN")
    parser.add_argument("--count", type=int, default=1500)
    parser.add_argument("--draw", type=int, default=0)
    parser.add_argument("--models", nargs="+", default=["1", "2"], help="STEPS or STEPS:CHOICE (SecondLookConfig)")
    args = parser.parse_args(argv)
    model = Model.pretrained()
    models = {}
    for spec in args.models:
        steps, _, choice = spec.partition(":")
        label = f"{steps} look{'s' * (int(steps) > 1)}" + (f", {choice}" if choice else "")
        models[label] = with_steps(model, int(steps), choice or "last")
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for spec in args.readings:
        path, pattern = spec.rsplit(":", 1)
        # The pattern's place in the readings' order seeds its samples: the same samples the readings scored.
        reading = next(r for r in readings([Path(path)], PATTERNS, [args.draw], args.count, scene, mask)
                       if r.pattern == pattern)
        images = [("truth", reading.truth_image)]
        for label, looking in models.items():
            z = looking.encode(reading.values, reading.directions)
            image = tonemap(render_linear(looking.decode(z)[0], scene))
            metrics = reading.metrics(image, mask)
            images.append((f"{label}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.2f}", image))
        grid.append((f"{reading.material}\n{pattern}", images))
    save_image_grid(grid, args.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
