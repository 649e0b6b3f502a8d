"""The pictures of docs/usage.md's "Edit a measured material": an edit between two real measurements, keeping each
(``frenbrdf edit``), and the plain latent interpolation between the same two (``frenbrdf edit --latent``).

Both run with the packaged model from 4000 samples of each measurement (seed 0), at t = 0, 0.25, 0.5, 0.75, 1;
each strip is framed by the measurements' own renders; ``ends-zoom.png`` enlarges the second material's
highlight in its measurement and at both edits' ends. The script prints each end's PSNR against its
measurement's render (from the commands' reports), and, for the kept edit (Model.edit, the same reconstructions),
how far each end is from its reconstruction over 200,000 random direction pairs and how even the path's steps are
over eleven positions. Run from the repository root (the measurements are not part of the repository:
../shared/data/rgl-measured/README.md)::

    python docs/edit/make_pictures.py            # or --data FOLDER, --a FILE --b FILE, --out FOLDER
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from pathlib import Path

import numpy as np
import torch

import frenbrdf
from frenbrdf.material.edit import edit_files
from frenbrdf.render import Scene, render

ROOT = Path(__file__).resolve().parents[2]
T = (0.0, 0.25, 0.5, 0.75, 1.0)


def path_steps(frames: np.ndarray) -> np.ndarray:
    """The root-mean-square change between neighbouring frames ``(T, ...)``: ``(T − 1,)``."""
    return np.sqrt(np.mean(np.diff(frames, axis=0).reshape(len(frames) - 1, -1) ** 2, axis=1))


def measure(a: Path, b: Path, samples: int = 4000, resolution: int = 128) -> dict:
    """The kept edit's figures: each end's largest error against its reconstruction (relative to f + ε), and the
    largest step of the renders and of the decoded weights over eleven positions, in medians of the steps."""
    model = frenbrdf.Model.pretrained()
    results = []
    for source in (a, b):  # as `frenbrdf edit` reconstructs them: seed 0, refine full
        measured = frenbrdf.read_samples(source, samples=samples, seed=0)
        results.append(model.reconstruct(measured.values, (measured.wi, measured.wo), refine="full"))
    rng = np.random.default_rng(0)
    wi, wo = (rng.normal(size=(200_000, 3)) for _ in range(2))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    wi, wo = wi / np.linalg.norm(wi, axis=1, keepdims=True), wo / np.linalg.norm(wo, axis=1, keepdims=True)
    ends = model.edit(*results, [0.0, 1.0])
    errors = {side: float(np.max(np.abs(ends[k](wi, wo) - result.nbrdf(wi, wo))
                                 / (result.nbrdf(wi, wo) + model.mapping.epsilon)))
              for k, (side, result) in enumerate(zip("ab", results, strict=True))}
    ts = np.linspace(0, 1, 11)
    path = model.edit(*results, ts)
    renders = np.stack([render(path[k], Scene(resolution=resolution)) for k in range(len(ts))])
    weights = np.stack([torch.cat([p.reshape(-1) for p in decoded.params]).numpy() for decoded in path.paths])
    smoothness = {}
    for what, frames in (("renders", renders), ("decoded_weights", weights)):
        steps = path_steps(frames)
        smoothness[what] = {"steps": [round(float(s), 5) for s in steps],
                            "largest_over_median": round(float(steps.max() / np.median(steps)), 3)}
    return {"end_error": errors, "smoothness_11_steps": smoothness}


def zoom(folder: Path, size: int = 256) -> None:
    """``ends-zoom.png``: material b's key highlight, twice enlarged: its measurement, the kept edit's end (t = 1)
    and the latent interpolation's, from the two strips (renders ``size`` wide, gaps a sixteenth of that)."""
    from PIL import Image

    gap = size // 16
    truth_b, end_b = size + gap + len(T) * size + gap, size + gap + (len(T) - 1) * size
    box = (size // 4, size // 8, 3 * size // 4, 5 * size // 8)  # the key light's highlight on the sphere
    kept, latent = (Image.open(folder / f"{name}.png").convert("RGB") for name in ("residual-edit", "latent-edit"))
    crops = [image.crop((x + box[0], box[1], x + box[2], box[3])).resize((2 * (box[2] - box[0]),) * 2, Image.NEAREST)
             for image, x in ((kept, truth_b), (kept, end_b), (latent, end_b))]
    sheet = Image.new("RGB", (sum(c.width for c in crops) + 2 * gap, crops[0].height), "white")
    for index, crop in enumerate(crops):
        sheet.paste(crop, (index * (crop.width + gap), 0))
    sheet.save(folder / "ends-zoom.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data" / "rgl-measured")
    parser.add_argument("--a", default="acrylic_felt_green_rgb.bsdf", help="the material at t = 0")
    parser.add_argument("--b", default="cg_sunflower_rgb.bsdf", help="the material at t = 1")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "edit")
    args = parser.parse_args()
    a, b = args.data / args.a, args.data / args.b
    summary = {}
    with tempfile.TemporaryDirectory() as scratch:
        for name, latent in (("residual-edit", False), ("latent-edit", True)):
            folder = Path(scratch) / name
            report = edit_files(a, b, folder, T, latent=latent, progress=False)
            shutil.copyfile(folder / "strip.png", args.out / f"{name}.png")
            summary[name] = {"refine": report["refine"]["budget"],
                             "ends_psnr": {side: round(m["psnr"], 2) for side, m in report["ends"].items()},
                             "ends_delta_e": {side: round(m["delta_e"], 2) for side, m in report["ends"].items()},
                             "ends_highlight_psnr": {side: round(m["highlight_psnr"], 2)
                                                     for side, m in report["ends"].items()}}
    zoom(args.out)
    summary["residual-edit"].update(measure(a, b))
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
