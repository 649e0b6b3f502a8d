"""look-ensemble's renders (README.md): materials through a pattern, the truth beside version 11's reading and the
three looks averaged, each titled with its PSNR / ΔE; 1,500 samples, draw 0 (the readings' samples).

    python research/results/look-ensemble/look.py FIGURE MATERIAL:PATTERN...
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from image_grid import save_image_grid  # noqa: E402
from pattern_readings import readings  # noqa: E402
from second_look import PATTERNS  # noqa: E402

from frenbrdf import Model  # noqa: E402
from frenbrdf.render import Scene, material_mask, render_linear, tonemap  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from read import latents, trained_looks  # noqa: E402


def main(figure: Path, specs: list[str]) -> int:
    model = Model.pretrained()
    looks = trained_looks(model)
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    grid = []
    for spec in specs:
        path, pattern = spec.rsplit(":", 1)
        reading = next(r for r in readings([Path(path)], PATTERNS, [0], 1500, scene, mask) if r.pattern == pattern)
        images = [("truth", reading.truth_image)]
        for name, z in latents(model, looks, reading).items():
            image = tonemap(render_linear(model.decode(z[0].numpy())[0], scene))
            metrics = reading.metrics(image, mask)
            images.append((f"{name}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.2f}", image))
        grid.append((f"{reading.material}\n{pattern}", images))
    save_image_grid(grid, figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1]), sys.argv[2:]))
