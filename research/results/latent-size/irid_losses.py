"""latent-size's addendum (README.md): each stage's loss on the samples (`Reconstruction.losses`: encoder, `latent`,
`full`'s weights) for `irid_flake_paint2` and measurements of other kinds, read by one run; 4,000 random valid bins,
seed 0.

    python research/results/latent-size/irid_losses.py local/rid/mf-f0-s0
"""

from __future__ import annotations

import sys

import frenbrdf

MEASUREMENTS = ("irid_flake_paint2_rgb", "vch_golden_yellow_rgb", "vch_ultra_pink_rgb", "paper_white_rgb",
                "cm_toxic_green_rgb", "satin_purple_rgb", "acrylic_felt_pink_rgb")


def main(run: str) -> None:
    model = frenbrdf.Model.load(run)
    for name in MEASUREMENTS:
        samples = frenbrdf.read_samples(f"../shared/data/rgl-measured/{name}.bsdf", samples=4000, seed=0)
        losses = model.reconstruct(samples.values, (samples.wi, samples.wo), refine="full").losses
        print(f"{name:24s} encoder {losses['encode']:.4f}  latent {losses['latent']:.4f}  full {losses['weights']:.4f}"
              f"  latent / full {losses['latent'] / losses['weights']:.1f}")


if __name__ == "__main__":
    main(sys.argv[1])
