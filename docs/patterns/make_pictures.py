"""Draws every sampling pattern of frenbrdf.io.patterns in Rusinkiewicz coordinates: docs/patterns/patterns.png.

For each pattern, 1,500 pairs drawn from seed 0: θ_h against θ_d, and φ_d (folded into [0°, 180°) by
reciprocity, as MERL's bins are) against θ_d; each pair coloured by its incidence angle θ_i. docs/usage.md
("Sampling patterns") shows the sheet. Run from the repository root::

    python docs/patterns/make_pictures.py            # or --out FOLDER, --count N
"""

from __future__ import annotations

import argparse
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the backend)
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

from frenbrdf.io.patterns import PATTERNS, sample_pattern  # noqa: E402
from frenbrdf.numerics.coords import directions_to_rusinkiewicz  # noqa: E402


def sheet(count: int = 1500, seed: int = 0, columns: int = 2):
    """The figure: one pair of panels (θ_h–θ_d, φ_d–θ_d) per pattern, ``columns`` patterns a row."""
    rows = -(-len(PATTERNS) // columns)
    figure, axes = plt.subplots(rows, 2 * columns, figsize=(4.2 * columns, 2.05 * rows), squeeze=False,
                                layout="constrained")
    for index, name in enumerate(PATTERNS):
        wi, wo = sample_pattern(name, count, np.random.default_rng(seed))
        theta_h, _, theta_d, phi_d = np.degrees(directions_to_rusinkiewicz(wi, wo)).T
        theta_i = np.degrees(np.arccos(np.clip(wi[:, 2], -1, 1)))
        left, right = axes[index // columns, 2 * (index % columns): 2 * (index % columns) + 2]
        for axis, y, label, top in ((left, theta_h, "θ_h", 90), (right, np.mod(phi_d, 180), "φ_d", 180)):
            points = axis.scatter(theta_d, y, c=theta_i, s=1.5, cmap="viridis", vmin=0, vmax=90, linewidths=0,
                                  rasterized=True)
            axis.set(xlim=(0, 90), ylim=(0, top), xticks=[0, 30, 60, 90], yticks=np.linspace(0, top, 4))
            axis.set_ylabel(f"{label} (°)", labelpad=1)
            axis.tick_params(labelsize=7)
            axis.xaxis.label.set_size(8)
            axis.yaxis.label.set_size(8)
        left.set_title(name, fontsize=9, loc="left", fontweight="bold")
        if index // columns == rows - 1:
            left.set_xlabel("θ_d (°)")
            right.set_xlabel("θ_d (°)")
    for axis in axes.flat[2 * len(PATTERNS):]:
        axis.set_visible(False)
    figure.colorbar(points, ax=axes, shrink=0.3, label="θ_i (°)", aspect=30)
    figure.suptitle(f"Sampling patterns ({count:,} pairs each, seed {seed}) in Rusinkiewicz coordinates",
                    fontsize=10)
    return figure


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=Path(__file__).resolve().parent, type=Path, help="folder for patterns.png")
    parser.add_argument("--count", type=int, default=1500, help="pairs per pattern (default 1500)")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    buffer = io.BytesIO()
    sheet(args.count).savefig(buffer, dpi=100)
    # A palette of 256 colours: a third of the bytes, no visible change (viridis and black on white).
    Image.open(buffer).convert("RGB").quantize(256).save(args.out / "patterns.png", optimize=True)
    print(f"wrote {args.out / 'patterns.png'}")


if __name__ == "__main__":
    main()
