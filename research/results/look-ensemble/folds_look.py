"""look-ensemble's fold renders (README.md): measurements through a pattern, the truth beside their fold run's reading
with one look and with three averaged (folds.py's models), each titled with its PSNR / ΔE; 1,500 samples, draw 5
(the fold reading's samples).

    python research/results/look-ensemble/folds_look.py FIGURE MATERIAL:PATTERN... [--runs local/rid --looks local/slf]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import save_image_grid  # noqa: E402
from look_rule import PATTERNS  # noqa: E402
from pattern_readings import readings  # noqa: E402

from frenbrdf.models.reconstruct import reconstruct  # noqa: E402
from frenbrdf.render import Scene, material_mask, render_linear, tonemap  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from folds import MEASURED, fold_models, fold_names  # noqa: E402


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("figure", type=Path)
    parser.add_argument("specs", nargs="+", help="MATERIAL:PATTERN, the material by its name in folds.json")
    parser.add_argument("--runs", type=Path, default=Path("local/rid"))
    parser.add_argument("--looks", type=Path, default=Path("local/slf"))
    args = parser.parse_args(argv)
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    folds = fold_names()
    grid = []
    for spec in args.specs:
        name, pattern = spec.rsplit(":", 1)
        fold = next(i for i, names in enumerate(folds) if name in names)
        reading = next(r for r in readings([MEASURED / f"{name}.bsdf"], PATTERNS, [5], 1500, scene, mask)
                       if r.pattern == pattern)
        images = [("truth", reading.truth_image)]
        for arm, model in fold_models(args.runs, args.looks, fold).items():
            image = tonemap(render_linear(reconstruct(model, reading.values, reading.directions,
                                                      refine="none").nbrdf, scene))
            metrics = reading.metrics(image, mask)
            images.append((f"{arm} look{'s' * (arm != 'one')}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.2f}",
                           image))
        grid.append((f"{name} (fold {fold})\n{pattern}", images))
    save_image_grid(grid, args.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
