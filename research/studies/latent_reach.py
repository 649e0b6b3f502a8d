"""How far can a latent space learnt from published NBRDF fits reach on real measurements?

    python research/studies/latent_reach.py ../shared/data/rgl-measured/*.bsdf \
        --fits ../shared/data/rgl-nbrdf --out research/results/real/latent-reach

The shipped model trained on published per-material NBRDF fits (of MERL and RGL materials), never on a
measurement. Each measurement's error under ``latent`` is split in two: how far the published fit of
the same material lies from the measurement (what the training data's kind loses), and how far the
best point of the latent space lies from that fit (what the space loses). For each measurement the
latent is refined for ``--steps`` steps (the space's best point, not the budget's) on ``--samples``
bins drawn from (a) the measurement and (b) the published fit's own table, and each result, and the
fit itself, is rendered and compared with the render of the measurement and of the fit.
Writes ``reach.md``, ``reach.json`` and ``reach.png`` (the renders of the first draw).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from frenbrdf.data.nbrdf_import import keras_merl_table, keras_nbrdf
from frenbrdf.io import read_material
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.keras import read_keras_nbrdf
from frenbrdf.io.sampling import sample_bins, truth_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import RefineConfig
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import render_sheet, run_metadata  # noqa: E402

PAIRS = (("fit", "measurement"), ("latent from the measurement", "measurement"),
         ("latent from the fit", "measurement"), ("latent from the fit", "fit"))


def reach(path: Path, fit_path: Path, model, *, samples: int, steps: int, seed: int,
          scene: Scene) -> tuple[dict, dict]:
    """PSNR and ΔE of each pair of :data:`PAIRS` for one measurement, and the four display images."""
    mask = material_mask(scene)
    truth = read_material(path)
    layers = read_keras_nbrdf(fit_path)
    fit_table = keras_merl_table(layers)  # the samples' source; the fit itself is rendered as the network
    config = RefineConfig(latent_steps=steps, latent_lr=3e-2, schedule="cosine", seed=seed, progress=False)
    images = {"measurement": tonemap(render_linear(truth, scene)),
              "fit": tonemap(render_linear(keras_nbrdf(layers), scene))}
    for name, source, table in (("measurement", truth, truth.table()), ("fit", fit_table, fit_table)):
        rng = np.random.default_rng(seed)
        drawn = truth_samples(source, sample_bins(table, rng, samples), rng)
        images[f"latent from the {name}"] = refined_reconstruction(model, drawn, scene, config)[1]
    return {f"{a} vs {b}": image_metrics(images[b], images[a], mask) for a, b in PAIRS}, images


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="+", help=".bsdf files")
    parser.add_argument("--fits", required=True, help="folder of the published fits (NAME.h5 beside NAME.bsdf)")
    parser.add_argument("--model", default="pretrained", help="'pretrained', a run folder or a checkpoint")
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--steps", type=int, default=1000, help="latent steps (the budget `latent` takes 200)")
    parser.add_argument("--draws", type=int, nargs="+", default=[0])
    parser.add_argument("--resolution", type=int, default=256)
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)

    model, scene = load_model(args.model), Scene(resolution=args.resolution)
    rows, grid = [], {}
    for path in tqdm([Path(p) for p in args.measurements], desc="measurements"):
        for draw in args.draws:
            scores, images = reach(path, Path(args.fits) / f"{path.stem}.h5", model, samples=args.samples,
                                   steps=args.steps, seed=draw, scene=scene)
            rows.append({"material": path.stem, "draw": draw, "scores": scores})
            if draw == args.draws[0]:
                grid[path.stem] = images

    pairs = [f"{a} vs {b}" for a, b in PAIRS]
    lines = [f"PSNR dB / ΔE, mean over draws {args.draws}; `latent`: {args.steps} steps on {args.samples} samples; "
             "each cell compares the first with the second.", "",
             "| material | " + " | ".join(pairs) + " |", "|---" * (len(pairs) + 1) + "|"]
    for material in [*dict.fromkeys(row["material"] for row in rows), None]:
        chosen = [row for row in rows if material in (None, row["material"])]
        cells = [f"{np.mean([r['scores'][p]['psnr'] for r in chosen]):.2f} / "
                 f"{np.mean([r['scores'][p]['delta_e'] for r in chosen]):.2f}" for p in pairs]
        lines.append(f"| {material or 'mean'} | " + " | ".join(cells) + " |")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "reach.md", "\n".join(lines) + "\n")
    save_json(out / "reach.json", {"run": run_metadata(), "model": args.model, "steps": args.steps, "rows": rows})
    render_sheet(grid, out / "reach.png")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
