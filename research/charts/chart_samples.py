"""Chart 4: reconstruction quality against the number of samples given to the encoder.

    python research/charts/chart_samples.py --runs merl-protocol/runs/{frenbrdf,nbrdf,hyperbrdf}/seed-0 \\
        --data merl-protocol/merl --name chart4_samples
    python research/charts/chart_samples.py --runs frenbrdf-demo/runs/{frenbrdf,nbrdf,hyperbrdf} \\
        --name chart4_samples_demo

Options: ``--samples 40 100 400 1000 4000 all`` (``all``: every measured bin, about 1.1
million), ``--seeds 3``, ``--resolution 128``, ``--max-materials 0`` (0: the whole test
split), ``--data DIR`` (default: the folder recorded in the runs' ``config.json``),
``--out research/figures``.

Each test material of the runs' common split is encoded from N random measured bins,
decoded, rendered and compared with the render of its true table, exactly as
``frenbrdf evaluate`` does it (:func:`frenbrdf.io.sampling.sample_bins`,
:func:`~frenbrdf.render.scoring.encode_and_render`, :func:`~frenbrdf.render.scoring.image_metrics`:
PSNR, SSIM and RMSE of the tone-mapped sphere renders over the lit material pixels).
Every N below ``all`` is drawn ``--seeds`` times, with the same bins for every method. A point of the chart is the mean
over the test materials, averaged over the draws; the band is ± one standard deviation
of that mean over the draws (``all`` has a single, exact draw).

Writes ``<out>/<name>.png`` and, beside it, ``<name>.csv`` (the plotted numbers) and
``<name>.json`` (those, the settings and every material's metrics).
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from frenbrdf.evaluation.evaluate import load_runs
from frenbrdf.io.merl import read_merl, valid_mask
from frenbrdf.io.sampling import sample_bins, truth_samples
from frenbrdf.render.renderer import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import encode_and_render, image_metrics

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import pyplot, run_metadata, save_chart, save_figure  # noqa: E402

#: Samples given to the encoder; ``None`` is every measured bin.
DEFAULT_COUNTS = (40, 100, 400, 1000, 4000, None)
METRICS = ("psnr", "ssim", "rmse")


def label(count: int | None) -> str:
    return "all" if count is None else str(count)


def samples_chart(run_dirs, out_dir, *, data: str | None = None, counts=DEFAULT_COUNTS, seeds: int = 3,
                  resolution: int = 128, max_materials: int = 0, name: str = "chart4_samples",
                  progress: bool = True) -> dict:
    """Measures reconstruction quality against the number of encoder samples; writes the chart and its data.

    Parameters
    ----------
    run_dirs
        Training runs of the same split, one per method.
    out_dir
        Folder of ``<name>.png``, ``<name>.csv`` and ``<name>.json``.
    data
        The materials' folder (default: the runs' own).
    counts
        Sample counts; ``None`` gives every measured bin (one draw).
    seeds
        Random draws per count.
    resolution
        Render size in pixels.
    max_materials
        Use at most this many test materials (0: all).

    Returns
    -------
    dict
        What ``<name>.json`` holds.
    """
    start = time.perf_counter()
    run = run_metadata()
    if seeds < 1 or not counts or any(c is not None and c < 1 for c in counts):
        raise ValueError(f"need seeds ≥ 1 and counts ≥ 1 (or None for all), got seeds={seeds}, counts={counts}")
    runs = load_runs(run_dirs, data, max_materials)
    scene = Scene(resolution=resolution)
    mask = material_mask(scene)  # the lit material pixels, as frenbrdf evaluate measures
    rows, valid_bins = [], {}
    with tqdm(total=len(runs.test) * len(counts), desc="samples chart", disable=not progress) as bar:
        for index, material in enumerate(runs.test):
            table = read_merl(runs.files[material])
            truth = tonemap(render_linear(table, scene))
            valid_bins[material] = int(valid_mask(table).sum())
            for count in counts:
                for seed in range(1 if count is None else seeds):
                    rng = np.random.default_rng([seed, count or 0, index])
                    bins = np.flatnonzero(valid_mask(table)) if count is None else sample_bins(table, rng, count)
                    drawn = truth_samples(table, bins, rng)
                    for method, model in runs.models.items():
                        _, image = encode_and_render(model, *drawn, scene)
                        rows.append({"method": method, "samples": label(count), "seed": seed, "material": material,
                                     **image_metrics(truth, image, mask)})
                bar.update()

    summary = summarise(rows, list(runs.models), counts, valid_bins)
    report = {"runs": [str(r) for r in runs.runs], "data": str(runs.data), "test_materials": runs.test,
              "samples": [label(c) for c in counts], "seeds": seeds, "resolution": resolution,
              "valid_bins": valid_bins, "summary": summary, "per_material": rows,
              "machine": f"{platform.machine()}, torch {torch.__version__} ({torch.get_num_threads()} threads)",
              "seconds": time.perf_counter() - start, "run": run}
    title = f"{runs.data.name}: {len(runs.test)} test materials, {resolution}² renders, {seeds} draws per count"
    save_chart(out_dir, name, summary, report, lambda path: plot(summary, path, title=title))
    return report


def summarise(rows: list[dict], methods: list[str], counts, valid_bins: dict[str, int]) -> list[dict]:
    """Per method and count: mean over materials per draw, then mean and std over the draws."""
    summary = []
    for method in methods:
        for count in counts:
            mine = [r for r in rows if r["method"] == method and r["samples"] == label(count)]
            draws = sorted({r["seed"] for r in mine})
            entry = {"method": method, "samples": label(count),
                     "n_samples": count if count is not None else float(np.mean(list(valid_bins.values()))),
                     "draws": len(draws), "materials": len({r["material"] for r in mine})}
            for metric in METRICS:
                per_draw = [np.mean([r[metric] for r in mine if r["seed"] == seed]) for seed in draws]
                entry[f"{metric}_mean"], entry[f"{metric}_std"] = float(np.mean(per_draw)), float(np.std(per_draw))
            summary.append(entry)
    return summary


def plot(summary: list[dict], path: Path, title: str = "") -> None:
    """PSNR and SSIM against the number of samples (log axis), one line and ±std band per method."""
    plt = pyplot()
    methods = list(dict.fromkeys(r["method"] for r in summary))
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for axis, metric, name in zip(axes, ("psnr", "ssim"), ("PSNR (dB) ↑", "SSIM ↑"), strict=True):
        for method in methods:
            mine = [r for r in summary if r["method"] == method]
            x = np.array([r["n_samples"] for r in mine])
            mean = np.array([r[f"{metric}_mean"] for r in mine])
            std = np.array([r[f"{metric}_std"] for r in mine])
            line, = axis.plot(x, mean, marker="o", label=method)
            axis.fill_between(x, mean - std, mean + std, color=line.get_color(), alpha=0.2)
        ticks = [r for r in summary if r["method"] == methods[0]]
        axis.set_xscale("log")
        axis.set_xticks([r["n_samples"] for r in ticks])
        axis.set_xticklabels([r["samples"] if r["samples"] != "all" else f"all\n({r['n_samples'] / 1e6:.2g}M)"
                              for r in ticks])
        axis.minorticks_off()
        axis.set_xlabel("samples given to the encoder")
        axis.set_ylabel(name)
        axis.grid(alpha=0.3)
    axes[0].legend()
    figure.suptitle(title, fontsize=10)
    figure.tight_layout()
    save_figure(figure, path)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", nargs="+", required=True, help="training run folders, one per method")
    parser.add_argument("--data", default=None, help="materials folder (default: the runs' own)")
    parser.add_argument("--out", type=Path, default=Path("research/figures"))
    parser.add_argument("--name", default="chart4_samples", help="file names: <name>.png, .csv, .json")
    parser.add_argument("--samples", nargs="+", default=[label(c) for c in DEFAULT_COUNTS],
                        help="sample counts, 'all' for every measured bin")
    parser.add_argument("--seeds", type=int, default=3, help="random draws per count")
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--max-materials", type=int, default=0, help="at most this many test materials (0: all)")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    counts = tuple(None if s == "all" else int(s) for s in args.samples)
    report = samples_chart(args.runs, args.out, data=args.data, counts=counts, seeds=args.seeds,
                           resolution=args.resolution, max_materials=args.max_materials, name=args.name,
                           progress=not args.quiet)
    print(f"{len(report['test_materials'])} materials, {report['seconds']:.0f} s → {args.out / args.name}.png")
    for row in report["summary"]:
        print(f"{row['method']:>10} {row['samples']:>5}: PSNR {row['psnr_mean']:.2f} ± {row['psnr_std']:.2f}, "
              f"SSIM {row['ssim_mean']:.4f} ± {row['ssim_std']:.4f}")


if __name__ == "__main__":
    main()
