"""Real measurements: how well a model gives back gonio-photometer measurements no training saw.

    python research/studies/real_measurements.py ../shared/data/rgl-measured/*.bsdf \
        --fits ../shared/data/rgl-nbrdf --model pretrained --out research/results/real

For each RGL ``.bsdf`` measurement: the model encodes it from ``--samples`` random valid MERL bins
(evaluated on the measurement itself, each pair in a random order), then refines on the same samples (``latent``: z only, the
latent space; ``full``: then the NBRDF's weights), and each result is rendered and compared with the
render of the measurement itself (not of a quantised table). Beside them, the published per-material
NBRDF fit of the same material (``--fits``: its Keras ``.h5``, fitted to 640k samples) and a
``fit-nbrdf`` fit to the same samples as the model saw (:func:`frenbrdf.data.fitting.fit_nbrdf_samples`).
Seconds: wall seconds of encoding and refinement (not of rendering; after one untimed warm-up), or of the
fit. Writes ``real.md`` (a table per material
and the means), ``real.json`` and ``real.png`` (truth | fit | encoder | latent | full, per row).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from frenbrdf.data.fitting import FitConfig, fit_nbrdf_samples
from frenbrdf.io import read_material
from frenbrdf.io.atomic import save_json, write_text
from frenbrdf.io.sampling import sample_bins, truth_samples
from frenbrdf.models.autoencoder import load_model
from frenbrdf.models.nbrdf import as_brdf
from frenbrdf.models.reconstruct import RefineConfig, refine_config
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import image_metrics, refined_reconstruction

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import render_sheet, run_metadata  # noqa: E402

COLUMNS = ("published fit", "fit-nbrdf", "encoder", "latent", "full")


def measure(path: Path, model, fits: Path | None, *, samples: int, seed: int, scene: Scene, fit_epochs: int,
            warm_up: bool = False):
    """The rows and images of one measurement (``warm_up``: one untimed refinement first: the first calls
    pay for thread pools and caches, not for refinement)."""
    truth = read_material(path)
    table = truth.table()
    truth_image = tonemap(render_linear(truth, scene))
    mask = material_mask(scene)
    rng = np.random.default_rng(seed)
    bins = sample_bins(table, rng, samples)
    drawn = truth_samples(truth, bins, rng)  # each pair in a random order: the measurement is not reciprocal
    if warm_up:
        refined_reconstruction(model, truth_samples(table, bins[:100], rng), Scene(resolution=8),
                               RefineConfig(latent_steps=2, weight_steps=2))
    images, rows = {"truth": truth_image}, {}
    published = fits / f"{path.stem}.h5" if fits else None
    if published is not None and published.exists():
        images["published fit"] = tonemap(render_linear(as_brdf(read_material(published)), scene))
    if fit_epochs:  # fit-nbrdf on the very samples the model sees
        start = time.perf_counter()
        fitted = fit_nbrdf_samples(*drawn, FitConfig(epochs=fit_epochs, seed=seed), progress=False)
        rows["fit-nbrdf"] = {"seconds": time.perf_counter() - start}
        images["fit-nbrdf"] = tonemap(render_linear(fitted, scene))
    for budget in ("none", "latent", "full"):
        config = dataclasses.replace(refine_config(budget), seed=seed, progress=False)
        result, image, _ = refined_reconstruction(model, drawn, scene, config)
        name = "encoder" if budget == "none" else budget
        rows[name] = {"seconds": sum(result.timings.values())}  # encoding and refinement, not the render
        images[name] = image
    for name, image in images.items():
        if name != "truth":
            rows.setdefault(name, {}).update(image_metrics(truth_image, image, mask))
    return rows, images


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measurements", nargs="+", help=".bsdf files")
    parser.add_argument("--model", default="pretrained", help="'pretrained', a run folder, a checkpoint or a packed "
                        "model's folder (card.json, model.pt, mapping.npz)")
    parser.add_argument("--fits", help="folder of the published per-material NBRDF fits (<name>.h5)")
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--resolution", type=int, default=256)
    parser.add_argument("--fit-epochs", type=int, default=2000,
                        help="fit-nbrdf passes over the samples (2000: about 16k steps, as its default 10 passes "
                        "make on a whole table); 0: no fit-nbrdf column")
    parser.add_argument("--out", required=True, help="folder for real.md, real.json, real.png")
    args = parser.parse_args(argv)
    model = load_model(args.model)
    scene = Scene(resolution=args.resolution)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results, grid = {}, {}
    for index, path in enumerate(tqdm([Path(p) for p in args.measurements], desc="measurements")):
        rows, images = measure(path, model, Path(args.fits) if args.fits else None, samples=args.samples,
                               seed=args.seed, scene=scene, fit_epochs=args.fit_epochs, warm_up=index == 0)
        results[path.stem] = rows
        grid[path.stem] = images
    means = {column: {key: float(np.mean(values)) for key in ("psnr", "delta_e", "seconds")
                      if (values := [r[column][key] for r in results.values() if key in r.get(column, {})])}
             for column in COLUMNS}
    report = {"run": run_metadata(), "model": args.model, "samples": args.samples, "seed": args.seed,
              "resolution": args.resolution, "materials": results, "mean": means}
    save_json(out / "real.json", report)
    write_text(out / "real.md", markdown(report))
    def title(name, column):
        metrics = results[name].get(column)
        return column if not metrics else f"{column}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.1f}"

    render_sheet(grid, out / "real.png", columns=["truth", *COLUMNS], title=title)
    print(markdown(report))
    return 0


def markdown(report: dict) -> str:
    lines = [f"Model `{report['model']}`, {report['samples']} samples (seed {report['seed']}), renders "
             f"{report['resolution']}²; PSNR dB / ΔE against the render of the measurement itself; seconds per material.",
             "", "| material | " + " | ".join(COLUMNS) + " |", "|---|" + "---|" * len(COLUMNS)]
    def cell(metrics):
        return f"{metrics['psnr']:.1f} / {metrics['delta_e']:.2f}" if metrics and "psnr" in metrics else "–"
    for name, rows in report["materials"].items():
        lines.append(f"| {name} | " + " | ".join(cell(rows.get(c)) for c in COLUMNS) + " |")
    lines.append("| **mean** | " + " | ".join(cell(report["mean"].get(c)) for c in COLUMNS) + " |")
    lines.append("| seconds | " + " | ".join(f"{report['mean'][c]['seconds']:.1f}" if "seconds" in report["mean"].get(c, {})
                                            else "–" for c in COLUMNS) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
