"""Is the encoder's gap on real measurements their noise? The encoder given a measurement's values
against the same bins of its published smooth NBRDF fit, both scored against the measurement.

    python research/studies/encoder_noise.py ../shared/data/rgl-measured/*.bsdf --fits ../shared/data/rgl-nbrdf

Prints, per measurement and draw, PSNR dB / ΔE of the encoder alone and with ``latent`` from each source.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from frenbrdf.io import read_material
from frenbrdf.io.sampling import as_table, sample_bins, truth_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.nbrdf import as_brdf
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="+", help=".bsdf files")
    parser.add_argument("--fits", required=True, help="folder of the published fits (<name>.h5)")
    parser.add_argument("--model", default="pretrained")
    parser.add_argument("--draws", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--resolution", type=int, default=128)
    args = parser.parse_args(argv)
    model, scene = load_model(args.model), Scene(resolution=args.resolution)
    mask = material_mask(scene)
    for path in map(Path, args.measurements):
        truth = read_material(path)
        truth_image = tonemap(render_linear(truth, scene))
        sources = {"measurement": truth,  # sampled itself, in both orders (truth_samples)
                   "fit": as_brdf(read_material(Path(args.fits) / f"{path.stem}.h5")).merl_table()}
        for draw in args.draws:
            rng = np.random.default_rng(draw)
            bins = sample_bins(as_table(truth), rng, 4000)
            cells = []
            for name, source in sources.items():
                drawn = truth_samples(source, bins, rng)
                for budget in ("none", "latent"):
                    config = dataclasses.replace(refine_config(budget), seed=draw, progress=False)
                    _, image, _ = refined_reconstruction(model, drawn, scene, config)
                    metrics = image_metrics(truth_image, image, mask)
                    cells.append(f"{name} {budget}: {metrics['psnr']:.1f} / {metrics['delta_e']:.2f}")
            print(path.stem, f"draw {draw}:", " | ".join(cells), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
