"""Chart 6: does frequency rectification help? FreNBRDF trained at several η, several seeds.

    python research/charts/chart_eta.py --data frenbrdf-demo/data --etas 0 5e-4 5e-3 0.05 0.5 --seeds 0 1 2

For every seed (its own split) and η, the FreNBRDF preset with the ``demo`` training length
(``--training``) is trained with that η (run folders in ``--work``, reused when complete),
then measured on the seed's **validation** materials as ``frenbrdf evaluate`` measures:
encode from 4000 samples, decode, render, PSNR/SSIM/RMSE/ΔE over the lit material pixels,
L_fre (normalised on the sphere, default settings for every run), and editing: every pair of
validation materials interpolated at t = 0.25, 0.5, 0.75 in the latent space and compared with
the blend of their true renders (``edit_psnr``, ``edit_delta_e``). Each η is compared with
η = 0 of the same seed (paired, 95 % t-interval over the seeds, :mod:`frenbrdf.evaluation.statistics`).
The gradient-norm ratio ‖∇(η·L_fre)‖ / ‖∇L_rec‖ of the first and last epoch says what each
η means as a strength. The issue's η grid {0.01, 0.1, 1, 10, 100} on the old mean over
coefficients is {5e-5, 5e-4, 5e-3, 0.05, 0.5} on the normalised L_fre (× 4π / 50²).

Writes ``<out>/<name>.{png,csv,json}`` (``--name``, default ``chart6_eta``).
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

from frenbrdf.data.folders import list_materials
from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.merl import read_merl
from frenbrdf.render.renderer import Scene, material_mask, render_linear
from frenbrdf.render.scoring import FrequencyMetric, edit_metrics, reconstruction_rows
from frenbrdf.training import Run, config_for, train

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import pyplot, run_metadata, save_chart, save_figure  # noqa: E402

METRICS = ("psnr", "ssim", "rmse", "delta_e", "lfre", "edit_psnr", "edit_delta_e")
EDIT_WEIGHTS = (0.25, 0.5, 0.75)


def train_or_reuse(cfg, data_cache: dict) -> Run:
    """The run of ``cfg``: trained, resumed, or reused when it already finished."""
    out = Path(cfg.out)
    if (out / "last.pt").exists():
        run = Run(out)
        if len(run.history) - 1 >= cfg.epochs:
            return run
        return train(cfg, resume=True, data_cache=data_cache)
    return train(cfg, overwrite=True, data_cache=data_cache)  # its own work folder


def measure(run: Run, files: dict, metric: FrequencyMetric, resolution: int, progress: bool) -> dict:
    names = sorted(run.split.val)
    model, latents = run.model(), {}
    rows = reconstruction_rows(model, [files[name] for name in names], resolution=resolution,
                               frequency_metric=metric, progress=progress, latents=latents)
    scene = Scene(resolution=resolution)
    mask = material_mask(scene)
    truth = {name: render_linear(read_merl(files[name]), scene) for name in names}
    edits = [edit_metrics(model, latents[a], latents[b], truth[a], truth[b], t, scene, mask)
             for a, b in itertools.combinations(names, 2) for t in EDIT_WEIGHTS]
    ratios = [e["train_gradient_ratio"] for e in run.history if "train_gradient_ratio" in e]
    means = {key: float(np.mean([r[key] for r in rows])) for key in METRICS if not key.startswith("edit_")}
    means |= {f"edit_{key}": float(np.mean([e[key] for e in edits])) for key in ("psnr", "delta_e")}
    return {**means,
            "ratio_first": ratios[0] if ratios else 0.0, "ratio_last": ratios[-1] if ratios else 0.0,
            "best_epoch": run.best_epoch, "val_materials": len(rows), "per_material": rows}


def summarise(runs: list[dict], etas, seeds) -> list[dict]:
    """One row per η: means over seeds and the paired difference to η = 0 of the same seed."""
    by = {(r["eta"], r["seed"]): r for r in runs}
    rows = []
    for eta in etas:
        row = {"eta": eta}
        for key in (*METRICS, "ratio_first", "ratio_last"):
            values = [by[eta, s][key] for s in seeds]
            row[key], row[f"{key}_sd"] = float(np.mean(values)), float(np.std(values, ddof=1)) if len(seeds) > 1 else 0
        for key in METRICS:
            d = paired_interval([by[eta, s][key] - by[0.0, s][key] for s in seeds])
            row.update({f"{key}_vs_0": d["mean"], f"{key}_vs_0_low": d["low"], f"{key}_vs_0_high": d["high"],
                        f"{key}_vs_0_significant": d["significant"]})
        rows.append(row)
    return rows


def markdown(rows: list[dict]) -> str:
    """The chart as a Markdown table: each metric's mean over seeds and its paired difference with η = 0."""
    def cell(r, key):
        if r["eta"] == 0:
            return f"{r[key]:.3g}"
        low, high = r[f"{key}_vs_0_low"], r[f"{key}_vs_0_high"]
        text = f"{r[f'{key}_vs_0']:+.2f} [{low:+.2f}, {high:+.2f}]" if low is not None else f"{r[f'{key}_vs_0']:+.2f}"
        return f"{r[key]:.3g} ({'**' + text + '**' if r[f'{key}_vs_0_significant'] else text})"

    keys = ("psnr", "delta_e", "lfre", "edit_psnr", "edit_delta_e")
    lines = ["| η | ‖∇(η·L_fre)‖/‖∇L_rec‖ first → last epoch | " + " | ".join(keys) + " |", "|---" * (len(keys) + 2) + "|"]
    lines += [f"| {r['eta']:g} | {r['ratio_first']:.3g} → {r['ratio_last']:.3g} | "
              + " | ".join(cell(r, key) for key in keys) + " |" for r in rows]
    return "\n".join(lines)


def draw(rows: list[dict], path: Path, caption: str) -> None:
    plt = pyplot()
    figure, axes = plt.subplots(1, 5, figsize=(22, 4.2))
    x = np.arange(len(rows))
    labels = [f"{r['eta']:g}" for r in rows]
    panels = (("psnr", "reconstruction PSNR − η=0 (dB)"), ("delta_e", "reconstruction ΔE − η=0"),
              ("lfre", "L_fre − η=0"), ("edit_psnr", "editing PSNR − η=0 (dB)"))
    for ax, (key, label) in zip(axes, panels, strict=False):  # the fifth axis is drawn below
        mean = np.array([r[f"{key}_vs_0"] for r in rows])
        low = np.array([r[f"{key}_vs_0_low"] if r[f"{key}_vs_0_low"] is not None else m
                        for r, m in zip(rows, mean, strict=True)])
        high = np.array([r[f"{key}_vs_0_high"] if r[f"{key}_vs_0_high"] is not None else m
                         for r, m in zip(rows, mean, strict=True)])
        ax.errorbar(x, mean, yerr=[mean - low, high - mean], fmt="o", capsize=4, color="#4c72b0")
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(x, labels)
        ax.set_xlabel("η (normalised L_fre)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    ax = axes[4]
    ratios = [(r["eta"], r["ratio_first"], r["ratio_last"]) for r in rows if r["eta"] > 0]
    ax.loglog([e for e, _, _ in ratios], [f for _, f, _ in ratios], "o-", label="first epoch")
    ax.loglog([e for e, _, _ in ratios], [la for _, _, la in ratios], "s--", label="last epoch")
    ax.axhline(1, color="k", lw=0.8)
    ax.set_xlabel("η")
    ax.set_ylabel("‖∇(η·L_fre)‖ / ‖∇L_rec‖")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    figure.suptitle("Chart 6 — FreNBRDF at several η against η = 0 of the same seed: paired mean and 95 % t-interval "
                    f"over seeds.\n{caption}", fontsize=9)
    figure.tight_layout()
    save_figure(figure, path, dpi=110)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", required=True, type=Path, help="folder of MERL files")
    parser.add_argument("--etas", type=float, nargs="+", default=[0.0, 5e-4, 5e-3, 0.05, 0.5])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--training", default="demo", help="training length of frenbrdf.presets (default demo)")
    parser.add_argument("--epochs", type=int, help="override the training length's epochs")
    parser.add_argument("--resolution", type=int, default=128, help="render size of the validation renders")
    parser.add_argument("--work", type=Path, default=Path("bench-results/eta"), help="run folders (reused)")
    parser.add_argument("--out", type=Path, default=Path("research/figures"))
    parser.add_argument("--name", default="chart6_eta", help="file name of the chart, without suffix")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args()
    if 0.0 not in args.etas:
        raise SystemExit("--etas must include 0, the baseline every η is compared with")
    start = time.perf_counter()
    files = {path.stem: path for path in list_materials(args.data)}
    metric = FrequencyMetric()
    runs = []
    for seed in args.seeds:
        data_cache: dict = {}
        for eta in args.etas:
            cfg = config_for("frenbrdf", training=args.training, data=str(args.data), seed=seed,
                             out=str(args.work / f"eta-{eta:g}" / f"seed-{seed}"), cache_dir=str(args.work / "cache"),
                             progress=not args.quiet, **({"epochs": args.epochs} if args.epochs else {}))
            cfg.loss.eta = eta
            run = train_or_reuse(cfg, data_cache)
            runs.append({"eta": eta, "seed": seed, "run": str(run.path),
                         **measure(run, files, metric, args.resolution, not args.quiet)})
            print(f"η {eta:g} seed {seed}: PSNR {runs[-1]['psnr']:.2f}, L_fre {runs[-1]['lfre']:.4g}, "
                  f"gradient ratio {runs[-1]['ratio_first']:.3g} → {runs[-1]['ratio_last']:.3g}", flush=True)
    rows = summarise(runs, args.etas, args.seeds)
    caption = (f"{Path(args.data).name}, {args.training} training, seeds {', '.join(map(str, args.seeds))}, "
               f"validation split, {time.perf_counter() - start:.0f} s.")
    report = {"chart": "eta", "data": str(args.data), "training": args.training, "seeds": args.seeds,
              "etas": args.etas, "run": run_metadata(), "rows": rows, "runs": runs}
    save_chart(args.out, args.name, rows, report, lambda path: draw(rows, path, caption))
    print(markdown(rows))
    print(f"wrote {args.out / args.name}.{{png,csv,json}}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
