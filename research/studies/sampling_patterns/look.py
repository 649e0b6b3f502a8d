"""Renders to look at: materials read through sampling patterns by several models, beside their truth.

    python research/studies/sampling_patterns/look.py --models pretrained local/v5/study/instruments-mean-s0 \\
        --labels v4 instruments-mean --look irid_flake_paint2_rgb:specular:1500 gold-paint:in-plane:300 \\
        --data local/v5/data --out research/results/sampling-patterns/look.png

Each ``--look MATERIAL:PATTERN:COUNT`` is a row: the truth (a measurement of ../shared/data/rgl-measured or a
table of ``--data``), then each model's encoder-only reconstruction from the same samples (draw 0, as
evaluate.sh draws them) and, with ``--latent``, each model's ``latent`` refinement, every image titled with its
render PSNR / ΔE.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from frenbrdf.io import read_material
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.io.sampling import as_table
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path[:0] = [str(Path(__file__).resolve().parents[1]), str(Path(__file__).resolve().parents[3] / "benches")]
from compare_models import condition_rng  # noqa: E402

from common import render_sheet  # noqa: E402

MEASUREMENTS = Path(__file__).resolve().parents[3].parent / "shared" / "data" / "rgl-measured"


def material_path(name: str, data: Path) -> Path:
    measured = MEASUREMENTS / f"{name}.bsdf"
    return measured if measured.exists() else data / f"{name}.binary"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", nargs="+", required=True)
    parser.add_argument("--labels", nargs="+", required=True)
    parser.add_argument("--look", nargs="+", required=True, metavar="MATERIAL:PATTERN:COUNT")
    parser.add_argument("--data", type=Path, required=True, help="folder of the tables")
    parser.add_argument("--latent", action="store_true", help="also each model's latent refinement")
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    if len(args.models) != len(args.labels):
        parser.error("give one label per model")
    models = {label: load_model(spec) for label, spec in zip(args.labels, args.models, strict=True)}
    scene = Scene(resolution=args.resolution)
    mask, sheet, titles = material_mask(scene), {}, {}
    budgets = ("none", "latent") if args.latent else ("none",)
    for look in args.look:
        name, pattern, count = look.split(":")
        truth = read_material(material_path(name, args.data))
        truth_image = tonemap(render_linear(truth, scene))
        drawn = pattern_samples(truth, pattern, int(count), condition_rng(0, pattern), table=as_table(truth))
        row = f"{name}\n{pattern} × {count}"
        sheet[row] = {"truth": truth_image}
        titles[row, "truth"] = "truth"
        for label, model in models.items():
            for budget in budgets:
                config = dataclasses.replace(refine_config(budget), seed=0, progress=False)
                _, image, _ = refined_reconstruction(model, drawn, scene, config)
                metrics = image_metrics(truth_image, image, mask)
                column = label if budget == "none" else f"{label} latent"
                sheet[row][column] = image
                titles[row, column] = f"{column}: {metrics['psnr']:.1f} dB / ΔE {metrics['delta_e']:.1f}"
    render_sheet(sheet, args.out, title=lambda row, column: titles.get((row, column), column))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
