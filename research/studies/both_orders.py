"""Samples of a measurement in one order of each pair (its MERL table's) or in both: what it changes.

    python research/studies/both_orders.py ../shared/data/rgl-measured/*.bsdf --draws 0 1 2 \
        --out research/results/real/both-orders

A MERL table holds one order (ω_i, ω_o) of each pair of directions, as reciprocity allows; a real
measurement is not reciprocal near grazing, so the table loses the other order's value. For each
measurement and draw, the same 4000 random valid bins are given to the shipped model twice: with the
table's values (one order, as every figure before this study) and with the measurement evaluated at
each bin's pair in a random order (:func:`frenbrdf.io.sampling.truth_samples`, what every command now
does); each budget (encoder, ``latent``, ``full``) is rendered and compared with the render of the
measurement itself; ``full`` on both orders fits an ordered NBRDF (``RefineConfig.keep_order``), and once more a
reciprocal one (keep_order False). Beside them, for scale, how far the measurement is from a reciprocal material: its
symmetrised form ½(f(ω_i, ω_o) + f(ω_o, ω_i)) and its transpose f(ω_o, ω_i) (the order a renderer that
takes ω_i towards the camera uses) rendered against it. Writes ``orders.json``, ``orders.md`` (means over
the draws, the change with a 95 % interval over the material × draw pairs) and ``orders.png`` (draw 0).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io import read_material
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.sampling import sample_bins, truth_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.reconstruct import refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import render_sheet, run_metadata  # noqa: E402

BUDGETS = ("none", "latent", "full")
ORDERS = ("one order", "both orders")
#: ``full`` on samples in both orders fits an ordered NBRDF (``RefineConfig.keep_order``); this column keeps it reciprocal.
RECIPROCAL = "full, both orders, reciprocal NBRDF"


def measure(path: Path, model, scene: Scene, draws: list[int]) -> tuple[dict, dict]:
    """``{column: [metrics of each draw]}`` of one measurement, and ``{column: display image}`` of the first draw."""
    truth = read_material(path)
    table = truth.table()
    mask = material_mask(scene)
    images = {"truth": tonemap(render_linear(truth, scene))}
    rows = {}
    for name, reordered in (("symmetrised", lambda wi, wo: (truth(wi, wo) + truth(wo, wi)) / 2),
                            ("transposed", lambda wi, wo: truth(wo, wi))):
        images[name] = tonemap(render_linear(reordered, scene))
        rows[name] = [image_metrics(images["truth"], images[name], mask)]
    for draw in draws:
        rng = np.random.default_rng(draw)
        bins = sample_bins(table, rng, 4000)
        for order, source in zip(ORDERS, (table, truth), strict=True):
            drawn = truth_samples(source, bins, rng)
            columns = [(f"{budget}, {order}", refine_config(budget)) for budget in BUDGETS]
            if order == "both orders":
                columns.append((RECIPROCAL, dataclasses.replace(refine_config("full"), keep_order=False)))
            for column, config in columns:
                _, image, _ = refined_reconstruction(model, drawn, scene, dataclasses.replace(config, seed=draw))
                rows.setdefault(column, []).append(image_metrics(images["truth"], image, mask))
                images.setdefault(column, image)
    return rows, images


#: The comparisons of the summary: (label, from column, to column).
CHANGES = [(budget, f"{budget}, one order", f"{budget}, both orders") for budget in BUDGETS] + [
    ("full, reciprocal NBRDF", "full, one order", RECIPROCAL),
    ("full: ordered against reciprocal NBRDF", RECIPROCAL, "full, both orders")]


def summary(results: dict) -> dict:
    """Per comparison of :data:`CHANGES`: both columns' mean PSNR and ΔE, and the change over the pairs."""
    out = {}
    for label, before, after in CHANGES:
        pairs = {key: [(a[key], b[key]) for rows in results.values()
                       for a, b in zip(rows[before], rows[after], strict=True)]
                 for key in ("psnr", "delta_e")}
        out[label] = {key: {"from": float(np.mean([a for a, _ in values])), "to": float(np.mean([b for _, b in values])),
                            "change": paired_interval([b - a for a, b in values])} for key, values in pairs.items()}
    return out


def markdown(report: dict) -> str:
    materials = list(report["materials"])
    mean = {name: np.mean([np.mean([m["psnr"] for m in rows[name]]) for rows in report["materials"].values()])
            for name in next(iter(report["materials"].values()))}
    lines = [f"Model `{report['model']}`, draws {report['draws']}, {report['resolution']}²; PSNR (dB) / ΔE against the "
             "measurement's own render, means over the draws.", "",
             "| column | " + " | ".join(materials) + " | mean PSNR |", "|---|" + "---|" * (len(materials) + 1)]
    for name in mean:
        cells = [f"{np.mean([m['psnr'] for m in rows[name]]):.2f} / {np.mean([m['delta_e'] for m in rows[name]]):.2f}"
                 for rows in report["materials"].values()]
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {mean[name]:.2f} |")
    lines += ["", "| comparison | PSNR | change (95 % interval) | ΔE | change |", "|---|---|---|---|---|"]
    for label, keys in report["summary"].items():
        cells = []
        for key in ("psnr", "delta_e"):
            s, c = keys[key], keys[key]["change"]
            cells += [f"{s['from']:.2f} → {s['to']:.2f}", f"{c['mean']:+.2f} [{c['low']:+.2f}, {c['high']:+.2f}]"]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="+", help=".bsdf files")
    parser.add_argument("--model", default="pretrained", help="'pretrained', a run folder, a checkpoint or a packed "
                        "model's folder")
    parser.add_argument("--draws", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--resolution", type=int, default=256)
    parser.add_argument("--out", required=True, help="folder for orders.json, orders.md and orders.png")
    args = parser.parse_args(argv)
    model, scene = load_model(args.model), Scene(resolution=args.resolution)
    results, grid = {}, {}
    for path in tqdm([Path(p) for p in args.measurements], desc="measurements"):
        results[path.stem], grid[path.stem] = measure(path, model, scene, args.draws)
    report = {"run": run_metadata(), "model": args.model, "draws": args.draws, "resolution": args.resolution,
              "materials": results, "summary": summary(results)}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    save_json(out / "orders.json", report)
    write_text(out / "orders.md", markdown(report))

    def title(name, column):
        metrics = results[name].get(column, [None])[0]
        return column if not metrics else f"{column}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.2f}"

    render_sheet(grid, out / "orders.png", title=title, fontsize=6)
    print(markdown(report))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
