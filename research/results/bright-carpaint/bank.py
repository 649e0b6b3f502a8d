"""The bright-carpaint study's bank: the ``features`` bank of ``frenbrdf synth --mix features --n 60 --seed 1``
with one change, its car paints' bases drawn up to a bright value (HSV value 0.05-0.9 instead of 0.05-0.6).

    python research/results/bright-carpaint/bank.py OUT

Every other draw is the same: the car paint sampler takes as many numbers from the generator as before, so
the 42 other materials, each car paint's hue, saturation, flakes and coat are those of the features bank
(``bank.json`` in OUT records the parameters).
"""

import colorsys
import sys

from frenbrdf.data import synth

BRIGHT_BASE = (0.05, 0.9)
"""HSV value of a car paint's base (the features bank: 0.05-0.6)."""


def bright_carpaint(rng):
    # synth._sample_carpaint with the base's value range widened; the same draws in the same order.
    hue = rng.uniform()
    colour = synth._saturated_colour(rng, hue, value=BRIGHT_BASE)
    flakes = synth._linear(colorsys.hsv_to_rgb((hue + rng.normal(0.0, 0.04)) % 1.0, rng.uniform(0.3, 1.0), 1.0))
    return synth._colour_name(colour), {"diffuse": colour, "flakes": rng.uniform(0.2, 0.8), "flake_colour": flakes,
                                        "flake_roughness": synth._log_uniform(rng, 0.08, 0.4), **synth._clear_coat(rng)}


if __name__ == "__main__":
    synth._SAMPLERS["carpaint"] = bright_carpaint
    synth.write_bank(sys.argv[1], n=60, seed=1, mix="features", progress=False)
