"""Real measurements beside a procedural bank: what each family was made to show.

    python research/charts/chart_features.py ../shared/data/rgl-measured/*.bsdf --out research/results/features.png
    python research/charts/chart_features.py --mix families --n 45 --seed 0 \
        ../shared/data/rgl-measured/{irid_flake_paint2,satin_purple,vch_ultra_pink}_rgb.bsdf \
        --out research/results/families.png
    python research/charts/chart_features.py --mix diffractive --n 15 --seed 0 --per-kind 5 \
        ../shared/data/rgl-measured/irid_flake_paint2_rgb.bsdf --out research/results/diffractive.png

Top row: the measurements (``frenbrdf.read_bsdf``, rendered directly), in the order of the kinds when each
imitates one. Below, one column per kind of ``frenbrdf synth --mix MIX`` (``features``: car paint,
retro-reflective, iridescent, fabric, coated; ``families``: iridescent, pearlescent, glitter), the first
``--per-kind`` materials of that kind in the bank of ``--n`` and ``--seed``, each on the metric renderer. A mix
of one kind (``diffractive``) is one row: the measurements, then its materials.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import frenbrdf
from frenbrdf.data import synth
from frenbrdf.render.renderer import Scene, render

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benches"))  # benches/
from common import pyplot, save_figure  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="*", help="RGL .bsdf files for the top row")
    parser.add_argument("--n", type=int, default=60)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--per-kind", type=int, default=3)
    parser.add_argument("--mix", choices=tuple(set(synth.MIXES) - {"default"}), default="features")
    parser.add_argument("--resolution", type=int, default=160)
    parser.add_argument("--out", default="features.png")
    args = parser.parse_args(argv)

    scene = Scene(resolution=args.resolution)
    bank = synth.material_bank(args.n, seed=args.seed, mix=args.mix)
    kinds = list(synth.MIXES[args.mix])
    # names end in the kind drawn (a glitter's analytic kind is "carpaint")
    members = {kind: [m for m in bank if m.name.endswith(f"-{kind}")][:args.per_kind] for kind in kinds}
    one_row = len(kinds) == 1
    rows, columns = ((1, len(args.measurements) + args.per_kind) if one_row else
                     (1 + args.per_kind, max(len(kinds), len(args.measurements))))
    plt = pyplot()
    figure, axes = plt.subplots(rows, columns, figsize=(3 * columns, 3 * rows), squeeze=False)
    for ax in axes.reshape(-1):
        ax.set_axis_off()
    for ax, path in zip(axes[0], args.measurements, strict=False):  # as many columns as kinds, or more
        ax.imshow(render(frenbrdf.read_bsdf(path), scene))
        ax.set_title(f"measured: {Path(path).stem}", fontsize=8)
    for column, kind in enumerate(kinds):
        for row, material in enumerate(members[kind], start=1):
            ax = axes[0, len(args.measurements) + row - 1] if one_row else axes[row, column]
            ax.imshow(render(synth.merl_table(material), scene))
            ax.set_title(material.name, fontsize=8)
    figure.tight_layout()
    save_figure(figure, args.out, dpi=55)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
