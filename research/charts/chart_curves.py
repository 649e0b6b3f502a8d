"""Chart 7: quality against training time, which checkpoint to keep, and what regularisation does.

    OMP_NUM_THREADS=1 python research/charts/chart_curves.py --data merl-protocol/merl --ood merl-protocol/bank

Every variant below is trained for ``--epochs`` (default 150, past the best epoch of the demo's
100) with the demo's batches, once per seed (each seed its own 70/10/20 split), rendering its
validation materials every ``--render-every`` epochs as ``frenbrdf evaluate`` does
(``TrainConfig.render_every``: 4000 samples each, 64², PSNR and ΔE over the lit pixels). The
history then holds, per epoch, the training and validation losses, the training wall time (the
renders excluded) and, every few epochs, the validation render PSNR: the learning curves.

- **Curves** (the chart): validation render PSNR against epochs and against training seconds, and
  the training and validation L_rec beside them, mean over seeds (band: min to max).
- **Model selection**: each run keeps the checkpoint of lowest validation loss (``best.pt``)
  and of highest validation render PSNR (``best-psnr.pt``) besides the last; all three are
  measured on the run's **test** materials, and the rules compared paired by run (95 % t-interval
  over the runs of every method and seed).
- **Regularisers** (issue 21): FreNBRDF with weight decay, encoder dropout, context-size jitter, and
  on the tables only (no augmentation), each paired with the default FreNBRDF of the same seed on
  the test split and, with ``--ood``, on the first ``--ood-materials`` materials of another folder.

Runs live in ``--work`` (reused when complete: a second call only measures). ``--train-only``
trains the named ``--variants`` and stops, so that several processes can share the training.
Writes ``<out>/<name>.{png,csv,json}`` and ``<name>_regularisers.md`` (``--name``, default ``chart7_curves``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from frenbrdf.data.folders import list_materials
from frenbrdf.evaluation.statistics import paired_interval
from frenbrdf.io.atomic import write_text
from frenbrdf.models.autoencoder import Model
from frenbrdf.render.scoring import reconstruction_rows
from frenbrdf.training import Run, config_for, train

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
from common import pyplot, run_metadata, save_chart, save_figure  # noqa: E402

#: Variant name → (method, overrides of its preset at the chosen length).
VARIANTS: dict[str, tuple[str, dict]] = {
    "frenbrdf": ("frenbrdf", {}),
    "nbrdf": ("nbrdf", {}),
    "hyperbrdf": ("hyperbrdf", {}),
    "frenbrdf, tables only": ("frenbrdf", {"augmentation": "paper"}),
    "frenbrdf, weight decay 0.1": ("frenbrdf", {"weight_decay": 0.1}),
    "frenbrdf, encoder dropout 0.1": ("frenbrdf", {"model": {"encoder": {"dropout": 0.1}}}),
    "frenbrdf, context jitter 0.25": ("frenbrdf", {"context_jitter": 0.25}),
}
METHODS = ("frenbrdf", "nbrdf", "hyperbrdf")
#: Checkpoint per selection rule.
RULES = {"validation loss": "best.pt", "validation render PSNR": "best-psnr.pt", "last epoch": "last.pt"}
METRICS = ("psnr", "delta_e")


def folder_name(variant: str) -> str:
    return variant.replace(", ", "-").replace(" ", "-")


def config(variant: str, seed: int, args):
    method, overrides = VARIANTS[variant]
    overrides = dict(overrides)
    augmentation = overrides.pop("augmentation", None)
    return config_for(method, training="demo", augmentation=augmentation, data=str(args.data), seed=seed,
                      epochs=args.epochs, render_every=args.render_every, select="loss",
                      out=str(args.work / folder_name(variant) / f"seed-{seed}"), progress=not args.quiet,
                      **overrides)  # nested overrides (``model``) merge into the preset's


def train_or_reuse(cfg) -> Run:
    """The run of ``cfg``: trained, resumed, or reused when it already finished."""
    out = Path(cfg.out)
    if (out / "last.pt").exists():
        run = Run(out)
        return run if len(run.history) - 1 >= cfg.epochs else train(cfg, resume=True)
    return train(cfg, overwrite=True)  # its own work folder: a run cut short is trained afresh


def score(checkpoint: Path, files: list[Path], resolution: int) -> dict:
    rows = reconstruction_rows(Model.load(checkpoint), files, resolution=resolution, frequency_metric=False,
                               progress=False)
    return {key: float(np.mean([r[key] for r in rows])) for key in METRICS} | {"per_material": rows}


def curves(run: Run) -> dict:
    history = [e for e in run.history if e["epoch"] >= 0]
    rendered = [e for e in history if "val_psnr" in e]
    return {"epoch": [e["epoch"] + 1 for e in history], "seconds": [e["seconds"] for e in history],
            "train_rec": [e["train_rec"] for e in history], "val_rec": [e["val_rec"] for e in history],
            "render_epoch": [e["epoch"] + 1 for e in rendered], "render_seconds": [e["seconds"] for e in rendered],
            "val_psnr": [e["val_psnr"] for e in rendered], "val_delta_e": [e["val_delta_e"] for e in rendered],
            "best_epoch": {rule: run.best_by(key)["epoch"] + 1 for rule, key in
                           (("validation loss", "loss"), ("validation render PSNR", "psnr"))}}


def measure(run: Run, args, ood_files: list[Path]) -> dict:
    test_files = [args.data / f"{name}.binary" for name in run.split.test]
    measured = {"run": str(run.path), "curves": curves(run),
                "test": {rule: score(run.path / file, test_files, args.resolution) for rule, file in RULES.items()}}
    if ood_files:
        measured["ood"] = score(run.path / RULES["validation loss"], ood_files, args.resolution)
    return measured


def paired(runs: dict, a: str, b: str, pick) -> dict:
    """b − a over the seeds both have: per metric, the paired mean and 95 % t-interval."""
    seeds = sorted(set(runs[a]) & set(runs[b]))
    return {key: {**paired_interval([pick(runs[b][s])[key] - pick(runs[a][s])[key] for s in seeds]),
                  "a": float(np.mean([pick(runs[a][s])[key] for s in seeds])),
                  "b": float(np.mean([pick(runs[b][s])[key] for s in seeds]))} | {"seeds": seeds}
            for key in METRICS}


def selection_rows(runs: dict) -> list[dict]:
    """Each rule against choosing by validation loss, paired over every (method, seed) run."""
    rows = []
    pairs = [(v, s) for v in METHODS if v in runs for s in runs[v]]
    for rule in RULES:
        row = {"rule": rule}
        for key in METRICS:
            values = [runs[v][s]["test"][rule][key] for v, s in pairs]
            base = [runs[v][s]["test"]["validation loss"][key] for v, s in pairs]
            d = paired_interval(list(np.subtract(values, base)))
            row |= {key: float(np.mean(values)), f"{key}_vs_loss": d["mean"], f"{key}_vs_loss_low": d["low"],
                    f"{key}_vs_loss_high": d["high"], f"{key}_vs_loss_significant": d["significant"]}
        rows.append(row)
    return rows


def interval(d: dict) -> str:
    text = f"{d['mean']:+.2f} [{d['low']:+.2f}, {d['high']:+.2f}]" if d["low"] is not None else f"{d['mean']:+.2f}"
    return f"**{text}**" if d["significant"] else text


def regulariser_markdown(runs: dict, report: dict) -> str:
    lines = ["| variant (FreNBRDF) | test PSNR | Δ PSNR vs default | test ΔE | Δ ΔE | OOD PSNR | Δ OOD PSNR | "
             "OOD ΔE | Δ OOD ΔE | best epoch (val loss) |", "|---" * 10 + "|"]
    default = list(runs["frenbrdf"].values())
    cells = ["frenbrdf (the default)", f"{np.mean([r['test']['validation loss']['psnr'] for r in default]):.2f}", "–",
             f"{np.mean([r['test']['validation loss']['delta_e'] for r in default]):.2f}", "–"]
    cells += ([f"{np.mean([r['ood']['psnr'] for r in default]):.2f}", "–",
               f"{np.mean([r['ood']['delta_e'] for r in default]):.2f}", "–"] if "ood" in default[0] else ["–"] * 4)
    lines.append("| " + " | ".join(cells + [", ".join(str(r["curves"]["best_epoch"]["validation loss"])
                                                     for r in default)]) + " |")
    for variant in VARIANTS:
        if variant in METHODS or variant not in runs:
            continue
        test = paired(runs, "frenbrdf", variant, lambda r: r["test"]["validation loss"])
        ood = paired(runs, "frenbrdf", variant, lambda r: r["ood"]) if "ood" in next(iter(runs[variant].values())) else None
        epochs = [r["curves"]["best_epoch"]["validation loss"] for r in runs[variant].values()]
        cells = [variant, f"{test['psnr']['b']:.2f}", interval(test["psnr"]), f"{test['delta_e']['b']:.2f}",
                 interval(test["delta_e"])]
        cells += ([f"{ood['psnr']['b']:.2f}", interval(ood["psnr"]), f"{ood['delta_e']['b']:.2f}",
                   interval(ood["delta_e"])] if ood else ["–"] * 4)
        lines.append("| " + " | ".join(cells + [", ".join(map(str, epochs))]) + " |")
    return (f"Regularisers: FreNBRDF trained {report['epochs']} epochs on {Path(report['data']).name}, seeds "
            f"{', '.join(map(str, report['seeds']))}; each paired with the default FreNBRDF of the same seed "
            "(best checkpoint by validation loss; Δ: mean and 95 % t-interval over the seeds, bold where it "
            "excludes 0). Test: each seed's test split. OOD: the first "
            f"{report['ood_materials']} materials of {Path(report['ood'] or '-').name}.\n\n" + "\n".join(lines) + "\n")


def draw(runs: dict, path: Path, caption: str) -> None:
    plt = pyplot()
    figure, axes = plt.subplots(1, 3, figsize=(16, 4.6))
    colours = dict(zip(VARIANTS, ("#c44e52", "#4c72b0", "#55a868", "#dd8452", "#8172b3", "#937860", "#da8bc3"),
                       strict=True))
    for variant, by_seed in runs.items():
        c = [r["curves"] for r in by_seed.values()]
        style = {"color": colours[variant], "lw": 1.8 if variant in METHODS else 1.0,
                 "ls": "-" if variant in METHODS else "--"}
        psnr = np.array([x["val_psnr"] for x in c])
        axes[0].plot(c[0]["render_epoch"], psnr.mean(0), label=variant, **style)
        axes[0].fill_between(c[0]["render_epoch"], psnr.min(0), psnr.max(0), color=colours[variant], alpha=0.12)
        seconds = np.array([x["render_seconds"] for x in c]).mean(0)
        axes[1].plot(seconds, psnr.mean(0), **style)
        if variant in (*METHODS, "frenbrdf, tables only"):
            axes[2].plot(c[0]["epoch"], np.mean([x["train_rec"] for x in c], 0), color=colours[variant], lw=0.8,
                         ls=":")
            axes[2].plot(c[0]["epoch"], np.mean([x["val_rec"] for x in c], 0), color=colours[variant], lw=1.2)
    axes[0].set(xlabel="epoch", ylabel="validation render PSNR (dB)")
    axes[1].set(xlabel="training seconds (one CPU thread, renders excluded)", ylabel="validation render PSNR (dB)")
    axes[2].set(xlabel="epoch", ylabel="L_rec: training (dotted), validation (solid)", yscale="log")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    figure.suptitle(f"Chart 7 — learning curves, mean over seeds (band: min–max).\n{caption}", fontsize=9)
    figure.tight_layout()
    save_figure(figure, path, dpi=110)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", required=True, type=Path, help="folder of MERL files to train on")
    parser.add_argument("--ood", type=Path, help="folder of materials none of the runs saw (out of distribution)")
    parser.add_argument("--ood-materials", type=int, default=40, help="the first N of --ood by name (default 40)")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS), metavar="VARIANT")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--epochs", type=int, default=150)
    parser.add_argument("--render-every", type=int, default=5)
    parser.add_argument("--resolution", type=int, default=128, help="render size of the test measurements")
    parser.add_argument("--work", type=Path, default=Path("bench-results/curves"), help="run folders (reused)")
    parser.add_argument("--out", type=Path, default=Path("research/figures"))
    parser.add_argument("--name", default="chart7_curves", help="file name of the chart, without suffix")
    parser.add_argument("--train-only", action="store_true", help="train the variants' runs and stop")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args()
    start = time.perf_counter()
    for seed in args.seeds:
        for variant in args.variants:
            run = train_or_reuse(config(variant, seed, args))
            print(f"{variant} seed {seed}: trained, best epoch {run.best_epoch + 1}", flush=True)
    if args.train_only:
        return 0
    ood_files = sorted(list_materials(args.ood))[:args.ood_materials] if args.ood else []
    runs: dict[str, dict[int, dict]] = {}
    for variant in args.variants:
        for seed in args.seeds:
            runs.setdefault(variant, {})[seed] = measure(Run(args.work / folder_name(variant) / f"seed-{seed}"), args,
                                                         ood_files)
            print(f"{variant} seed {seed}: test PSNR by rule " + ", ".join(
                f"{rule} {m['psnr']:.2f}" for rule, m in runs[variant][seed]["test"].items()), flush=True)
    rows = [{"variant": v, "seed": s, "best_epoch_loss": r["curves"]["best_epoch"]["validation loss"],
             "best_epoch_psnr": r["curves"]["best_epoch"]["validation render PSNR"],
             "final_val_psnr": r["curves"]["val_psnr"][-1], "seconds": r["curves"]["seconds"][-1],
             **{f"test_{key}_{rule.replace(' ', '_')}": r["test"][rule][key] for rule in RULES for key in METRICS},
             **({f"ood_{key}": r["ood"][key] for key in METRICS} if "ood" in r else {})}
            for v, by_seed in runs.items() for s, r in by_seed.items()]
    report = {"chart": "curves", "data": str(args.data), "ood": str(args.ood) if args.ood else None,
              "ood_materials": len(ood_files), "epochs": args.epochs, "seeds": args.seeds,
              "render_every": args.render_every, "run": run_metadata(), "selection": selection_rows(runs),
              "rows": rows, "runs": runs}
    caption = (f"{args.data.name}, {args.epochs} epochs of the demo's batches, seeds {', '.join(map(str, args.seeds))}; "
               f"validation renders every {args.render_every} epochs; {time.perf_counter() - start:.0f} s to measure.")
    save_chart(args.out, args.name, rows, report, lambda path: draw(runs, path, caption))
    write_text(args.out / f"{args.name}_regularisers.md", regulariser_markdown(runs, report))
    for row in report["selection"]:
        print(f"{row['rule']}: test PSNR {row['psnr']:.2f} (vs validation loss {row['psnr_vs_loss']:+.2f} "
              f"[{row['psnr_vs_loss_low']}, {row['psnr_vs_loss_high']}])")
    print(regulariser_markdown(runs, report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
