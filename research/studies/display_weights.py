"""`latent` with each sample's loss weighted as the display image weighs it: an exploration (decides nothing).

The latent stage fits the samples by a cos θ_i-weighted L1 in the log-relative space, where an error of 10 % costs
the same on a dark back-scatter sample as on a highlight. The renders that every table scores are tone-mapped
(``clip(radiance, 0, 1) ** (1 / 2.2)``): a small error Δ ln f on a sample moves its pixel by about
g / 2.2 · Δ ln f, with g = min(E · f · cos θ_i, 1) ** (1 / 2.2) the display value it lights (E the key light's
irradiance, about 2). latent-gap found that the samples' loss and the renders do not rank latents alike. This runs
:mod:`compare_models` with stage 1's per-sample weight (its cos θ_i factor) replaced by

    ``cos``    cos θ_i (today's, the baseline),
    ``gP``     (min(E · lum(f) · cos θ_i, 1)) ** P, normalised to mean 1 over the samples (P = 0.45: the display),
    ``cosgP``  cos θ_i · the same,

by patching :func:`frenbrdf.models.reconstruct.mapped_samples` in this process only (stage 2 and the reported
losses change with it; ``latent`` has no stage 2).

    python research/studies/display_weights.py WEIGHT [compare_models.py's arguments]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import frenbrdf.models.reconstruct as reconstruct_module
from frenbrdf.render.scoring import LUMINANCE

sys.path.insert(0, str(Path(__file__).parent))
import compare_models  # noqa: E402

#: The key light's irradiance (frenbrdf.render.lighting.KEY_LIGHT): where the display clamps.
KEY_IRRADIANCE = 2.1


def display_weights(values: np.ndarray, cos_in: np.ndarray, power: float) -> np.ndarray:
    """(min(E · lum(f) · cos θ_i, 1)) ** power per sample, normalised to mean 1 (a floor keeps black samples in)."""
    lit = np.minimum(KEY_IRRADIANCE * (values @ LUMINANCE) * cos_in, 1.0)
    weights = np.maximum(lit, 1e-3) ** power
    return weights / weights.mean()


def patched(kind: str):
    original = reconstruct_module.mapped_samples

    def mapped_samples(mapping, values, directions):
        mapped, coords, cos_in = original(mapping, values, directions)
        if kind == "cos":
            return mapped, coords, cos_in
        power = float(kind.removeprefix("cos").removeprefix("g"))
        weights = display_weights(np.asarray(values, dtype=np.float64), cos_in, power)
        return mapped, coords, (cos_in * weights if kind.startswith("cos") else weights)

    return mapped_samples


def main() -> int:
    kind, argv = sys.argv[1], sys.argv[2:]
    reconstruct_module.mapped_samples = patched(kind)
    return compare_models.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
