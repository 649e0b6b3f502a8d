"""One arm of the doubled-φ_d study (research/results/doubled-phi-d): train the NBRDF baseline at the demo's length
with the network's D input folded by reciprocity (``fold``, today's), with φ_d doubled (``doubled``) or doubled
with D's in-plane length kept (``scaled``), then read
its test split and the seam across the plane of incidence on the 19 measurements.

    python research/studies/doubled_phi_d.py --arm fold|doubled|scaled --seed 0 --data BANK --work WORK

``doubled`` replaces D = (x, y, z) by (x² − y², 2xy, z) everywhere the package computes the network's input
(``nbrdf.fold_difference`` and ``nbrdf.merl_bin_inputs``), in this process only: it is invariant under the fold's
half-turn (x, y) → (−x, −y), so every network is reciprocal and continuous across φ_d = 0 and π by construction.
Nothing in the package changes; the Mitsuba kernel and the viewer are not patched and not used here.
"""

from __future__ import annotations

import argparse
import functools
import sys
from pathlib import Path

import numpy as np

from frenbrdf.models import editing, nbrdf

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paired_arms import train_and_read  # noqa: E402


def doubled_difference(d: np.ndarray) -> np.ndarray:
    """D with φ_d doubled: (x² − y², 2xy, z), the same for a pair and its reverse, continuous everywhere."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack([x * x - y * y, 2 * x * y, z], axis=-1)


def scaled_difference(d: np.ndarray) -> np.ndarray:
    """D with φ_d doubled and its in-plane length kept: (cos 2φ_d, sin 2φ_d) · sin θ_d, and D_z."""
    doubled = doubled_difference(d)
    length = np.hypot(d[..., 0], d[..., 1])
    scale = np.divide(1.0, length, out=np.zeros_like(length), where=length > 1e-12)
    return np.concatenate([doubled[..., :2] * scale[..., None], doubled[..., 2:]], axis=-1)


ARMS = {"fold": None, "doubled": doubled_difference, "scaled": scaled_difference}


def use_input(difference) -> None:
    """Patches this process's NBRDF inputs to read D through ``difference`` (before any is computed: both are
    cached on first use)."""
    plain_inputs = nbrdf.merl_bin_inputs

    @functools.cache
    def patched_bin_inputs():
        above, inputs = plain_inputs()
        inputs = np.concatenate([inputs[:, :3], difference(inputs[:, 3:])], axis=-1)
        inputs.flags.writeable = False
        return above, inputs

    nbrdf.fold_difference = difference
    nbrdf.merl_bin_inputs = editing.merl_bin_inputs = patched_bin_inputs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arm", choices=tuple(ARMS), required=True)
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--data", required=True, help="the demo's bank (frenbrdf synth BANK)")
    parser.add_argument("--work", type=Path, required=True)
    parser.add_argument("--measured", default="../shared/data/rgl-measured")
    args = parser.parse_args()
    if ARMS[args.arm] is not None:
        use_input(ARMS[args.arm])
    train_and_read(args.arm, args.seed, args.data, args.work, Path(args.measured), ("none", "latent"))


if __name__ == "__main__":
    main()
