"""Chart 8: test-time refinement — render quality against seconds per material.

    python research/charts/chart_refine.py --run runs/frenbrdf --ood merl/ --name chart8_refine

For each material: the encoder alone, the latent refined (``--latent-steps``), the latent and
then the NBRDF's weights refined (``--weight-steps``, after ``--full-latent-steps`` latent
steps), all from ``--samples`` random valid bins (:func:`frenbrdf.models.reconstruct.reconstruct`),
and a per-material NBRDF fitted from scratch on every valid bin (``fit-nbrdf``,
:func:`frenbrdf.data.fitting.fit_nbrdf`, ``--fit-epochs``). Each is rendered and compared with the
render of the true table (:func:`frenbrdf.render.scoring.image_metrics`: PSNR and ΔE over the lit
material pixels). Seconds are the process's CPU seconds per material (refinement: all stages,
encoding included; fitting: the fit), which on one torch thread (``OMP_NUM_THREADS=1``) is what
an idle core takes, whatever else shares the machine; wall seconds are kept beside them.

Materials: the run's test split ("like the training set") and, with ``--ood DIR``, every
MERL file of another folder ("unlike it"). A point is the mean over a set's materials.
``--max-materials N`` keeps the first N of each set (0: all). The named budgets of
``frenbrdf.models.reconstruct.BUDGETS`` are to be set at the knee of this chart.

Writes ``<out>/<name>.png``, ``.csv`` (the plotted means) and ``.json`` (those, every
material's numbers, the settings and the run block).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from frenbrdf import Run
from frenbrdf.data.fitting import FitConfig, fit_nbrdf
from frenbrdf.data.folders import list_materials
from frenbrdf.io import read_samples
from frenbrdf.models.reconstruct import RefineConfig, reconstruct
from frenbrdf.render.renderer import Scene, material_mask, render
from frenbrdf.render.scoring import image_metrics

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import pyplot, run_metadata, save_chart, save_figure  # noqa: E402

FAMILIES = ("encoder", "latent", "full", "fit-nbrdf")


def settings(latent_steps, full_latent_steps: int, weight_steps, fit_epochs) -> list[tuple[str, str, object]]:
    """(family, budget label, RefineConfig or FitConfig) of every point of a material."""
    points = [("encoder", "0", RefineConfig())]
    points += [("latent", str(n), RefineConfig(latent_steps=n)) for n in latent_steps]
    points += [("full", f"{full_latent_steps}+{n}", RefineConfig(latent_steps=full_latent_steps, weight_steps=n))
               for n in weight_steps]
    points += [("fit-nbrdf", f"{e} epochs", FitConfig(epochs=e)) for e in fit_epochs]
    return points


def measure(model, path: Path, points, samples: int, seed: int, scene: Scene) -> list[dict]:
    """Every point of one material: seconds, PSNR and ΔE."""
    measured = read_samples(path, samples=samples, seed=seed)
    truth, mask = render(measured.table, scene), material_mask(scene)
    rows = []
    for family, budget, config in points:
        start, cpu_start = time.perf_counter(), time.process_time()
        if family == "fit-nbrdf":
            nbrdf = fit_nbrdf(measured.table, config, progress=False)
        else:
            nbrdf = reconstruct(model, measured.values, (measured.wi, measured.wo), refine=config).nbrdf
        seconds, wall = time.process_time() - cpu_start, time.perf_counter() - start
        metrics = image_metrics(truth, render(nbrdf, scene), mask)
        rows.append({"material": path.stem, "family": family, "budget": budget, "seconds": seconds,
                     "wall_seconds": wall,
                     "psnr": metrics["psnr"], "delta_e": metrics["delta_e"]})
    return rows


def refine_chart(run_dir, out_dir, *, ood: str | None = None, samples: int = 4000, latent_steps=(25, 100, 400),
                 full_latent_steps: int = 100, weight_steps=(100, 300, 1000, 3000), fit_epochs=(1, 3, 10),
                 max_materials: int = 0, resolution: int = 128, seed: int = 0, name: str = "chart8_refine",
                 progress: bool = True, points=None, data: str | None = None, draw_chart=None) -> dict:
    """Measures chart 8 and writes it; returns what ``<name>.json`` holds.

    ``points`` ((family, label, config) per point) replaces the ones the step counts make; ``data``
    is the run's data folder where it has moved since training; ``draw_chart(rows, path)`` replaces
    :func:`draw`."""
    run = Run(run_dir)
    model = run.model()
    files = {path.stem: path for path in list_materials(data or run.data)}
    sets = {"test split": [files[n] for n in sorted(run.split.test)]}
    if ood:
        sets["other folder"] = list_materials(ood)
    sets = {label: paths[: max_materials or None] for label, paths in sets.items()}
    points = points or settings(latent_steps, full_latent_steps, weight_steps, fit_epochs)
    scene = Scene(resolution=resolution)
    # One untimed pass first: the first call pays for caches and thread pools, not for refinement.
    measure(model, next(iter(sets.values()))[0], [("full", "warm-up", RefineConfig(latent_steps=2, weight_steps=2))],
            samples, seed, scene)
    details = []
    for label, paths in sets.items():
        for path in tqdm(paths, desc=label, disable=not progress):
            details += [{"set": label, **row} for row in measure(model, path, points, samples, seed, scene)]
    rows = []
    for label in sets:
        for family, budget, _ in points:
            chosen = [d for d in details if d["set"] == label and d["family"] == family and d["budget"] == budget]
            rows.append({"set": label, "family": family, "budget": budget, "materials": len(chosen),
                         **{key: float(np.mean([d[key] for d in chosen])) for key in ("seconds", "psnr", "delta_e")}})
    report = {"run": run_metadata(), "model": str(run.path), "method": run.method, "samples": samples,
              "sets": {label: [p.stem for p in paths] for label, paths in sets.items()},
              "resolution": resolution, "seed": seed, "points": rows, "materials": details}
    save_chart(out_dir, name, rows, report, lambda path: (draw_chart or draw)(rows, path))
    return report


def draw(rows: list[dict], path: Path) -> None:
    plt = pyplot()
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = dict(zip(FAMILIES, ("#444444", "#4c72b0", "#dd8452", "#55a868"), strict=True))
    for axis, metric, label in ((axes[0], "psnr", "render PSNR (dB) ↑"), (axes[1], "delta_e", "ΔE (CIEDE2000) ↓")):
        # One or two sets (in and out of distribution), a style each.
        for style, set_label in zip(("-o", "--s"), dict.fromkeys(r["set"] for r in rows), strict=False):
            for family in FAMILIES:
                chosen = [r for r in rows if r["set"] == set_label and r["family"] == family]
                if chosen:
                    axis.plot([r["seconds"] for r in chosen], [r[metric] for r in chosen], style,
                              color=colours[family], label=f"{family} ({set_label})")
        axis.set_xscale("log")
        axis.set_xlabel("CPU seconds per material (one thread)")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    figure.suptitle("Chart 8: test-time refinement against fitting from scratch", fontsize=10)
    figure.tight_layout()
    save_figure(figure, path)


def add_run_arguments(parser: argparse.ArgumentParser, *, name: str, max_materials: int) -> None:
    """The arguments every refinement chart takes: the run, where its data is, the materials, the output."""
    parser.add_argument("--run", required=True, help="training run folder")
    parser.add_argument("--data", help="the run's data folder, where it has moved since training")
    parser.add_argument("--ood", help="folder of MERL files unlike the training set (all of them are used)")
    parser.add_argument("--max-materials", type=int, default=max_materials, help="the first N of each set (0: all)")
    parser.add_argument("--out", default=str(Path(__file__).resolve().parents[2] / "docs" / "charts"))
    parser.add_argument("--name", default=name)
    parser.add_argument("--quiet", action="store_true")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_run_arguments(parser, name="chart8_refine", max_materials=0)
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--latent-steps", type=int, nargs="+", default=[25, 100, 400])
    parser.add_argument("--full-latent-steps", type=int, default=100)
    parser.add_argument("--weight-steps", type=int, nargs="+", default=[100, 300, 1000, 3000])
    parser.add_argument("--fit-epochs", type=int, nargs="*", default=[1, 3, 10])
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    refine_chart(args.run, args.out, ood=args.ood, samples=args.samples, latent_steps=args.latent_steps,
                 full_latent_steps=args.full_latent_steps, weight_steps=args.weight_steps,
                 fit_epochs=args.fit_epochs, max_materials=args.max_materials, resolution=args.resolution,
                 seed=args.seed, name=args.name, progress=not args.quiet, data=args.data)
    print(f"wrote {Path(args.out) / args.name}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
