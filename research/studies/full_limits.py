"""What limits ``full`` on real measurements: the number of samples, or the number of weight steps?

    OMP_NUM_THREADS=1 python research/studies/full_limits.py ../shared/data/rgl-measured/*.bsdf \
        --samples 4000 40000 --weight-steps 1000 3000 --draws 0 1 2 --out research/results/full-limits

For each measurement, sample draw, sample count, weight-step count and NBRDF width: ``full`` (the named
budget with only ``weight_steps`` and ``width`` changed, ``RefineConfig.width``; more samples than the
budget's batch are drawn in random mini-batches), with its seconds of encoding and refinement,
rendered and compared with the render of the measurement itself, as ``real_measurements.py`` does.
Beside them, ``table lookup``: the measurement's own MERL table (whose bins every sample is drawn from)
rendered by the metric renderer's table lookup, for scale. A diagnostic, not a choice of budget: the
four measurements judge the budgets and never choose them. Writes ``limits.json``, ``limits.md`` and
``limits.png`` (the renders of the first draw: truth, table lookup, each variant).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from itertools import product
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from frenbrdf.io import read_material
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.sampling import as_table, sample_bins, truth_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import render_sheet, run_metadata  # noqa: E402

TABLE = "table lookup"


def measure(path: Path, model, scene: Scene, *, samples: list[int], weight_steps: list[int], widths: list[int | None],
            draws: list[int]) -> tuple[dict, dict]:
    """``{variant: [metrics of each draw]}`` for one measurement (the table lookup: one entry, no draw), and
    ``{column: image}`` of the first draw."""
    truth = read_material(path)
    table = as_table(truth)
    images = {"truth": tonemap(render_linear(truth, scene))}
    mask = material_mask(scene)
    rows = {}
    if table is not truth:  # a measurement: its table is a second, quantised truth; a MERL file is its own
        images[TABLE] = tonemap(render_linear(table, scene))
        rows[TABLE] = [image_metrics(images["truth"], images[TABLE], mask)]
    for count, draw in product(samples, draws):
        rng = np.random.default_rng(draw)
        drawn = truth_samples(truth, sample_bins(table, rng, count), rng)
        for steps, width in product(weight_steps, widths):
            config = dataclasses.replace(refine_config("full"), weight_steps=steps, width=width, seed=draw)
            result, image, _ = refined_reconstruction(model, drawn, scene, config)
            metrics = image_metrics(images["truth"], image, mask) | {"loss": result.losses["weights"],
                                                                     "seconds": sum(result.timings.values())}
            rows.setdefault(variant_name(count, steps, width), []).append(metrics)
            images.setdefault(variant_name(count, steps, width), image)  # the first draw's
    return rows, images


def mean_over_materials(results: dict, variant: str, key: str) -> float | None:
    """The mean over the materials of each one's mean over its draws (None where the variant has no such key)."""
    means = [np.mean([m[key] for m in rows[variant]]) for rows in results.values()
             if variant in rows and key in rows[variant][0]]
    return float(np.mean(means)) if means else None


def variant_name(samples: int, steps: int, width: int | None = None) -> str:
    return f"{samples} samples, {steps} weight steps" + (f", width {width}" if width else "")


def draw_renders(grid: dict, results: dict, path: Path) -> None:
    """One row per measurement: the truth, then every column with its PSNR / ΔE in that draw."""
    def title(name, column):
        metrics = results[name].get(column, [None])[0]
        short = column.replace(" samples, ", " s., ").replace(" weight steps", " steps")
        return short if not metrics else f"{short}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.2f}"

    render_sheet(grid, path, title=title, fontsize=6)


def cell(metrics: list[dict] | None) -> str:
    """PSNR / ΔE, the mean over the draws ("–" where a material has no such row)."""
    if not metrics:
        return "–"
    return f"{np.mean([m['psnr'] for m in metrics]):.2f} / {np.mean([m['delta_e'] for m in metrics]):.2f}"


def markdown(report: dict) -> str:
    materials = list(report["materials"])
    lines = [f"Model `{report['model']}`, draws {report['draws']}, {report['resolution']}²; PSNR (dB) / ΔE, the mean "
             f"over the draws; seconds of encoding and refinement ({report['threads']} threads), the mean over all.",
             "",
             "| variant | " + " | ".join(materials) + " | mean | seconds |", "|---|" + "---|" * (len(materials) + 2)]
    for variant, mean in report["mean"].items():
        cells = [cell(report["materials"][name].get(variant)) for name in materials]
        seconds = f"{mean['seconds']:.2f}" if "seconds" in mean else "–"
        overall = f"{mean['psnr']:.2f} / {mean['delta_e']:.2f}"
        lines.append(f"| {variant} | " + " | ".join(cells) + f" | {overall} | {seconds} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="+", help=".bsdf files or MERL tables")
    parser.add_argument("--model", default="pretrained", help="'pretrained', a run folder, a checkpoint or a packed "
                        "model's folder")
    parser.add_argument("--samples", type=int, nargs="+", default=[4000, 40000])
    parser.add_argument("--weight-steps", type=int, nargs="+", default=[1000, 3000])
    parser.add_argument("--widths", type=int, nargs="+", default=[0],
                        help="hidden widths of the refined NBRDF (RefineConfig.width); 0: the model's own")
    parser.add_argument("--draws", type=int, nargs="+", default=[0])
    parser.add_argument("--resolution", type=int, default=256)
    parser.add_argument("--out", required=True, help="folder for limits.json, limits.md and limits.png")
    args = parser.parse_args(argv)
    model = load_model(args.model)
    scene = Scene(resolution=args.resolution)
    widths = [width or None for width in args.widths]
    results, grid = {}, {}
    for path in tqdm([Path(p) for p in args.measurements], desc="measurements"):
        results[path.stem], grid[path.stem] = measure(path, model, scene, samples=args.samples,
                                                      weight_steps=args.weight_steps, widths=widths, draws=args.draws)
    variants = list(dict.fromkeys(variant for rows in results.values() for variant in rows))
    mean = {variant: {key: value for key in ("psnr", "delta_e", "seconds")
                      if (value := mean_over_materials(results, variant, key)) is not None} for variant in variants}
    report = {"run": run_metadata(), "model": args.model, "draws": args.draws, "resolution": args.resolution,
              "threads": torch.get_num_threads(),
              "materials": results, "mean": mean}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    save_json(out / "limits.json", report)
    write_text(out / "limits.md", markdown(report))
    draw_renders(grid, results, out / "limits.png")
    print(markdown(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
