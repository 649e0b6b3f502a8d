"""Sweeps of training configurations: the frequency-loss and capacity charts (charts 2, 3).

Each chart trains a list of :class:`~frenbrdf.evaluation.variants.Variant` s — the FreNBRDF preset
with one setting varied at a time around the default — with
:func:`frenbrdf.evaluation.variants.run_sweep`, which trains (or resumes, or skips when measured
already) and measures each one; this module adds the chart variants, the training-step
time of each variant (:func:`add_step_time`) and the throughput of the decoded NBRDFs
(:func:`add_throughput`), both timed with ``benches/step_timing.py`` as :class:`TimingSettings`
says, the combination of seeds, the Pareto front, and the figures.

A sweep may be repeated with other seeds (each seed its own split): :func:`combine_seeds`
averages a variant over them and compares it with the default of the same seed, whose
spread over the seeds shows how much a single training run varies.

- Chart 2 (:func:`frequency_variants`): one-at-a-time variation of L_fre's lmax, number
  of θ_h slices, k and σ around the default.
- Chart 3 (:func:`frenbrdf.evaluation.variants.capacity_variants`): NBRDF hidden sizes and latent
  sizes around the default, with the Pareto front of PSNR against bytes per material
  (:func:`pareto_front`).

Used by ``research/charts/chart_frequency.py`` and ``research/charts/chart_capacity.py``; not part of the
installed package.
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from frenbrdf.configs import from_dict
from frenbrdf.data.folders import list_materials
from frenbrdf.evaluation.variants import MeasureSettings, Variant, base_config, capacity_variants, run_sweep
from frenbrdf.io.atomic import save_json
from frenbrdf.io.jsonfile import read_json
from frenbrdf.models.autoencoder import Model
from frenbrdf.presets import TRAINING
from frenbrdf.training import TrainConfig

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[2] / "benches")]  # its folder, benches/
import common  # noqa: E402
from step_timing import nbrdf_throughput, time_training_step  # noqa: E402

#: File names of the charts in the output folder (``.png``, ``.csv``, ``.json``).
CHART_NAMES = {"frequency": "chart2_frequency", "capacity": "chart3_capacity"}



def spread_slices(n: int) -> tuple[int, ...]:
    """``n`` distinct θ_h bin indices (0 … 89) spread evenly: a step of 96/n, 4 → (0, 24, 48, 72), the
    default; from n = 16 on a step of 96/n would pass bin 89, and the step is 90/n."""
    if not 1 <= n <= 90:
        raise ValueError(f"the number of slices must be in 1 … 90, got {n}")
    span = 96 if (n - 1) * 96 // n < 90 else 90
    return tuple(i * span // n for i in range(n))


def frequency_variants(lmax=(24, 89), slices=(2, 8), k=(1, 4), sigma=(0.025, 0.1)) -> list[Variant]:
    """Chart 2: the default, then L_fre's lmax, slice count, k and σ varied one at a time."""
    def frequency(**keys):
        return {"loss": {"frequency": keys}}

    variants = [Variant("default", "default", None)]
    variants += [Variant(f"lmax={v}", "lmax", v, frequency(lmax=v)) for v in lmax]
    variants += [Variant(f"slices={n}", "slices", n, frequency(slices=list(spread_slices(n)))) for n in slices]
    variants += [Variant(f"k={v}", "k", v, frequency(k=v)) for v in k]
    variants += [Variant(f"sigma={v}", "sigma", v, frequency(sigma=v)) for v in sigma]
    return variants


@dataclass
class TimingSettings:
    """What a sweep times besides what :class:`~frenbrdf.evaluation.variants.MeasureSettings` measures."""

    steps: int = 20
    """Training steps timed per variant (0: no step timing), on the first seed only; the fastest counts (least
    disturbed by other processes; ``research/studies/train_step.py`` reports the median)."""
    materials: int = 16
    """Materials of the data folder the step timing reads (enough for one batch)."""
    throughput_queries: int = 1 << 18
    """Queries of the decoded NBRDFs' throughput measurement (chart 3; 0: not measured)."""


def timing_data(data: str | os.PathLike, work: str | os.PathLike, n: int) -> Path:
    """A folder ``WORK/timing-data`` linking the first ``n`` materials of ``data``: enough for one timed batch,
    fast to read."""
    folder = Path(work) / "timing-data"
    folder.mkdir(parents=True, exist_ok=True)
    wanted = {path.name: path.resolve() for path in list_materials(data)[:n]}
    for link in folder.glob("*.binary"):
        if link.name not in wanted or link.resolve() != wanted[link.name]:
            link.unlink()
    for name, target in wanted.items():
        if not (folder / name).exists():
            (folder / name).symlink_to(target)
    return folder


STEP_KEYS = ("step_ms", "step_without_fre_ms", "fre_share", "timing_threads")


def add_step_time(row: dict, work: str | os.PathLike, timing: TimingSettings | None = None,
                  data_cache: dict | None = None) -> dict:
    """Sets the training-step time of ``row`` (a result row of a run in ``WORK/runs/``): ``step_ms``,
    ``step_without_fre_ms`` and ``fre_share`` (what L_fre adds; NaN without L_fre), ``timing_threads``.

    The row's config steps on :func:`timing_data` (``timing.materials`` materials), timed by
    :func:`step_timing.time_training_step` (the fastest of ``timing.steps``). The times are kept in the run's
    ``step_time.json``: a sweep started again reuses them (same config, steps and torch threads).
    ``data_cache``: the mapped timing materials, shared between the variants of a sweep. Returns ``row``.
    """
    timing = TimingSettings() if timing is None else timing
    saved_path = Path(row["run"]) / "step_time.json"
    wanted = {"key": row["key"], "steps": timing.steps, "materials": timing.materials,
              "timing_threads": torch.get_num_threads()}
    if saved_path.exists():
        try:
            saved = read_json(saved_path, "step time file")
            if all(saved.get(k) == v for k, v in wanted.items()):
                row.update({k: saved[k] for k in STEP_KEYS})
                return row
        except (ValueError, KeyError):
            pass  # a damaged file is timed again
    cfg = from_dict(TrainConfig, row["config"], f"variant {row['name']}")
    cfg.data = str(timing_data(row["config"]["data"], work, timing.materials))
    cfg.cache_dir, cfg.progress = cfg.cache_dir or str(Path(work) / "cache"), False
    timed = time_training_step(cfg, timing.steps, data_cache=data_cache, statistic=min)
    row.update(step_ms=1e3 * timed["step_s"], step_without_fre_ms=1e3 * timed.get("step_without_fre_s", math.nan),
               fre_share=timed.get("fre_added_share", math.nan), timing_threads=wanted["timing_threads"])
    save_json(saved_path, {**wanted, **{k: row[k] for k in STEP_KEYS}})
    return row


def add_throughput(rows: list[dict], queries: int = 1 << 18, repeats: int = 40) -> list[dict]:
    """Sets ``throughput_qps`` of each row, its run's decoded NBRDF timed with all the others'."""
    nbrdfs = {}
    for row in rows:
        model = Model.load(row["run"])
        nbrdfs[row["name"]] = model.decode(np.zeros(model.config.encoder.latent))  # the values do not change speed
    speeds = nbrdf_throughput(nbrdfs, queries, repeats)
    return [{**row, "throughput_qps": speeds[row["name"]]} for row in rows]


def pareto_front(rows: list[dict], maximise=("psnr",), minimise=("bytes_per_material", "latent_bytes")) -> list[bool]:
    """Whether each row is on the front: no other row is at least as good on every objective and better on one."""
    def at_least_as_good(a, b):
        return all(a[m] >= b[m] for m in maximise) and all(a[m] <= b[m] for m in minimise)

    def better(a, b):
        return any(a[m] > b[m] for m in maximise) or any(a[m] < b[m] for m in minimise)

    return [not any(at_least_as_good(other, row) and better(other, row) for other in rows if other is not row)
            for row in rows]


CSV_COLUMNS = ("name", "axis", "value", "hidden", "nbrdf_weights", "bytes_per_material", "latent", "latent_bytes",
               "lmax", "n_slices", "slices", "k", "sigma", "seeds", "psnr", "psnr_by_seed", "psnr_delta",
               "psnr_delta_by_seed", "psnr_delta_spread", "ssim", "rmse", "lfre", "val_rec", "val_fre", "step_ms",
               "step_without_fre_ms", "fre_share", "throughput_qps", "front", "train_s", "key")


#: Measurements averaged over the seeds of a variant (those present: step time and throughput come from one).
MEAN_KEYS = ("psnr", "ssim", "rmse", "lfre", "val_rec", "val_fre", "step_ms", "step_without_fre_ms", "fre_share",
             "throughput_qps", "train_s")


def _present(value) -> bool:
    return value is not None and not (isinstance(value, float) and math.isnan(value))


def combine_seeds(runs: list[dict]) -> list[dict]:
    """One row per variant from its runs (one per seed): means, and PSNR paired with the default.

    The seed fixes the split, so PSNRs of different seeds differ by their validation
    materials as much as by anything else; ``psnr_delta`` compares a variant with the
    default of the same seed (paired), and the spread of that difference over the seeds
    (``psnr_delta_spread``, max − min) shows how much one training run varies.
    """
    default = {r["seed"]: r["psnr"] for r in runs if r["axis"] == "default"}
    rows = []
    for name in dict.fromkeys(r["name"] for r in runs):
        mine = sorted((r for r in runs if r["name"] == name), key=lambda r: r["seed"])
        row = {k: v for k, v in mine[0].items() if k not in ("per_material", "seed")}
        for key in MEAN_KEYS:
            values = [r[key] for r in mine if _present(r.get(key))]
            row[key] = float(np.mean(values)) if values else None
        deltas = [r["psnr"] - default[r["seed"]] for r in mine if r["seed"] in default]
        row.update(seeds=[r["seed"] for r in mine], psnr_by_seed=[r["psnr"] for r in mine],
                   runs=[r.get("run") for r in mine], psnr_delta=float(np.mean(deltas)) if deltas else None,
                   psnr_delta_by_seed=deltas, psnr_delta_spread=float(np.ptp(deltas)) if len(deltas) > 1 else None)
        rows.append(row)
    return rows


def _csv_rows(rows: list[dict]) -> list[dict]:
    """The chart rows as CSV cells: sequences joined, floats to 6 significant digits."""
    cells = []
    for row in rows:
        cell = {}
        for column in CSV_COLUMNS:
            value = row.get(column, "")
            if isinstance(value, (list, tuple)):
                separator = "x" if column in ("hidden", "slices", "value") else ";"
                value = separator.join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in value)
            elif isinstance(value, float):
                value = f"{value:.6g}"
            cell[column] = "" if value is None else value
        cells.append(cell)
    return cells


def save_chart(kind: str, runs: list[dict], out_dir: str | os.PathLike, meta: dict | None = None) -> dict[str, Path]:
    """Writes a chart's JSON, CSV and PNG to ``out_dir``.

    ``runs``: result rows of :func:`run_variant`, one per variant and seed. The CSV and the
    JSON's ``rows`` hold one row per variant (:func:`combine_seeds`; what is plotted and what
    ``select`` reads); the JSON's ``runs`` every run's measurements, per material included.
    """
    if kind not in CHART_NAMES:
        raise ValueError(f"chart kind must be one of {sorted(CHART_NAMES)}, got {kind!r}")
    runs = [{"seed": 0, **run} for run in runs]
    rows = combine_seeds(runs)
    if kind == "capacity":
        for row, on_front in zip(rows, pareto_front(rows), strict=True):
            row["front"] = on_front
    plot = _plot_frequency if kind == "frequency" else _plot_capacity
    return common.save_chart(out_dir, CHART_NAMES[kind], _csv_rows(rows),
                             {"chart": kind, **(meta or {}), "rows": rows, "runs": runs},
                             lambda path: plot(rows, path, meta or {}))


FREQUENCY_AXES = (("lmax", "lmax", "L_fre band limit lmax"), ("slices", "n_slices", "θ_h slices"),
                  ("k", "k", "kNN neighbours k"), ("sigma", "sigma", "kNN width σ"))


def _axis_points(rows: list[dict], axis: str, column: str) -> list[dict]:
    """The rows varying ``axis`` plus the default, sorted by the varied value."""
    points = [r for r in rows if r["axis"] in (axis, "default")]
    return sorted(points, key=lambda r: r[column])


def _plot_frequency(rows: list[dict], path: Path, meta: dict) -> None:
    plt = common.pyplot()
    metrics = (("step_ms", "training step (ms)"), ("psnr", "validation PSNR (dB)"), ("lfre", "validation L_fre"))
    figure, axes = plt.subplots(len(metrics), len(FREQUENCY_AXES), figsize=(13, 8.5), squeeze=False)
    for col, (axis, column, label) in enumerate(FREQUENCY_AXES):
        points = _axis_points(rows, axis, column)
        x = np.arange(len(points))
        for row_index, (metric, metric_label) in enumerate(metrics):
            ax = axes[row_index, col]
            y = [p.get(metric, math.nan) for p in points]
            ax.plot(x, y, "o-", color="#4c72b0", label="with L_fre" if metric == "step_ms" else None)
            if metric == "psnr" and any(_present(p.get("psnr_delta_spread")) for p in points):
                ax.errorbar(x, y, yerr=[(p.get("psnr_delta_spread") or 0) / 2 for p in points], fmt="none",
                            ecolor="#4c72b0", capsize=3)
            if metric == "step_ms":
                ax.plot(x, [p.get("step_without_fre_ms", math.nan) for p in points], "s--", color="#999999",
                        label="without L_fre")
                ax.set_ylim(bottom=0)
            for xi, p in zip(x, points, strict=True):
                if p["axis"] == "default":
                    ax.plot(xi, p.get(metric, math.nan), "o", markersize=11, markerfacecolor="none", color="#dd8452")
            ax.set_xticks(x, [str(p[column]) for p in points])
            if row_index == len(metrics) - 1:
                ax.set_xlabel(label)
            if col == 0:
                ax.set_ylabel(metric_label)
            ax.grid(alpha=0.3)
        axes[0, col].legend(fontsize=7, loc="lower right")
    figure.suptitle("Chart 2 — frequency loss: cost and effect (one setting varied at a time around the default, "
                    f"circled).\n{meta.get('caption', '')} Error bars: half the spread over seeds of the PSNR "
                    "difference to the default of the same seed.", fontsize=9)
    figure.tight_layout()
    common.save_figure(figure, path, dpi=110)


def _label(row: dict) -> str:
    return f"6→{'→'.join(map(str, row['hidden']))}→3, z{row['latent']}"


def _plot_capacity(rows: list[dict], path: Path, meta: dict) -> None:
    plt = common.pyplot()
    panels = (("bytes_per_material", "psnr", "bytes per material (NBRDF float32 weights)", "validation PSNR (dB)"),
              ("throughput_mqps", "psnr", "NBRDF evaluation throughput (million queries/s, 1 CPU thread)",
               "validation PSNR (dB)"),
              ("bytes_per_material", "ssim", "bytes per material", "validation SSIM"),
              ("bytes_per_material", "lfre", "bytes per material", "validation L_fre"))
    rows = [{**r, "throughput_mqps": r["throughput_qps"] / 1e6} if _present(r.get("throughput_qps")) else r
            for r in rows]
    figure, axes = plt.subplots(2, 2, figsize=(12, 9), squeeze=False)
    colours = {16: "#55a868", 40: "#4c72b0", 64: "#c44e52"}
    for ax, (x_key, y_key, x_label, y_label) in zip(axes.flat, panels, strict=True):
        if not all(r.get(x_key) is not None and r.get(y_key) is not None for r in rows):
            ax.set_visible(False)
            continue
        for r in rows:
            ax.plot(r[x_key], r[y_key], "o", color=colours.get(r["latent"], "#8172b2"), markersize=7,
                    markeredgecolor="k" if r.get("front") else "none")
            if y_key == "psnr" and _present(r.get("psnr_delta_spread")):
                ax.errorbar(r[x_key], r[y_key], yerr=r["psnr_delta_spread"] / 2, fmt="none", ecolor="#999999",
                            capsize=3)
            ax.annotate(_label(r), (r[x_key], r[y_key]), fontsize=6.5, xytext=(4, 3), textcoords="offset points")
        if y_key == "psnr":
            if x_key == "bytes_per_material":
                front = [r for r in rows if r.get("front")]
                label = "Pareto front: no smaller material has a higher PSNR"
            else:  # the front of PSNR against speed
                on_front = pareto_front(rows, maximise=("psnr", x_key), minimise=())
                front = [r for r, on in zip(rows, on_front, strict=True) if on]
                label = "Pareto front: no faster NBRDF has a higher PSNR"
            ordered = sorted(front, key=lambda r: r[x_key])
            ax.step([r[x_key] for r in ordered], [r[y_key] for r in ordered],
                    where="post" if x_key == "bytes_per_material" else "pre", color="k", alpha=0.5, label=label)
            ax.legend(fontsize=7, loc="best")
        if x_key == "bytes_per_material":
            ax.set_xscale("log")
            ticks = sorted({r[x_key] for r in rows})
            ax.set_xticks(ticks, [str(t) for t in ticks], rotation=45, fontsize=7)
            ax.minorticks_off()
        ax.set_xlabel(x_label)
        ax.set_ylabel(y_label)
        ax.grid(alpha=0.3)
    figure.suptitle("Chart 3 — capacity: quality against size and speed of the decoded NBRDF (colour: latent size "
                    "16 green / 40 blue / 64 red; edged: on the PSNR-vs-bytes front).\n"
                    f"{meta.get('caption', '')} Error bars: half the spread over seeds of the PSNR difference to the "
                    "default of the same seed.", fontsize=9)
    figure.tight_layout()
    common.save_figure(figure, path, dpi=110)


def chart_main(kind: str, argv: list[str] | None = None, doc: str | None = None) -> int:
    """Command line of ``benches/chart_{frequency,capacity}.py``: sweep (resumable), then write the chart."""
    import argparse

    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", required=True, type=Path, help="folder of MERL files")
    parser.add_argument("--out", type=Path, default=Path("research/figures"), help="chart folder (default research/figures)")
    parser.add_argument("--work", type=Path, default=Path("bench-results/sweeps"),
                        help="run folders, shared by the charts and kept for resuming (default bench-results/sweeps)")
    parser.add_argument("--epochs", type=int, default=TRAINING["sweep"]["epochs"],
                        help=f"training epochs per run (default {TRAINING['sweep']['epochs']})")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0],
                        help="training seeds (default 0); each fixes its own split, and a variant's PSNR is also "
                        "given against the default of the same seed; step times are measured on the first")
    parser.add_argument("--threads", type=int, default=1, help="torch threads for training and timing (default 1)")
    defaults = TimingSettings()
    parser.add_argument("--timing-steps", type=int, default=defaults.steps,
                        help=f"training steps timed per variant, the fastest counts (default {defaults.steps}; 0: "
                        "no step timing)")
    parser.add_argument("--timing-materials", type=int, default=defaults.materials,
                        help=f"materials of --data the step timing reads (default {defaults.materials})")
    parser.add_argument("--throughput-queries", type=int, default=defaults.throughput_queries,
                        help=f"queries of the decoded NBRDFs' throughput, chart 3 (default "
                        f"{defaults.throughput_queries}; 0: not measured)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    variants = frequency_variants() if kind == "frequency" else capacity_variants()
    measure = MeasureSettings(progress=not args.quiet)
    timing = TimingSettings(steps=args.timing_steps, materials=args.timing_materials,
                            throughput_queries=args.throughput_queries)
    start = time.perf_counter()
    base = base_config(args.data, epochs=args.epochs, seed=args.seeds[0])
    seeds = ", ".join(map(str, args.seeds))
    meta = {"data": str(args.data), "epochs": base.epochs, "seeds": args.seeds, "torch_threads": args.threads,
            "training": {k: getattr(base, k) for k in TRAINING["sweep"]},
            "measure": {k: v for k, v in vars(measure).items() if k != "progress"}, "timing": asdict(timing),
            "caption": f"{base.epochs} epochs each, {Path(args.data).name}, validation split, seed(s) {seeds}."}

    def save(runs):  # after every variant: a partial chart is there to look at while the sweep runs
        save_chart(kind, runs, args.out, {**meta, "sweep_s": round(time.perf_counter() - start, 1)})

    runs: list[dict] = []
    timing_cache: dict = {}  # the mapped timing materials, shared by the variants
    for i, seed in enumerate(args.seeds):
        base = base_config(args.data, epochs=args.epochs, seed=seed)

        def on_row(done, before=tuple(runs), first=i == 0):
            if first and timing.steps:  # step time does not depend on the seed: timed on the first only
                add_step_time(done[-1], args.work, timing, timing_cache)  # the row run_sweep returns, in place
            save([*before, *done])

        runs += run_sweep(variants, base, args.work, measure, on_row=on_row)
    if kind == "capacity" and timing.throughput_queries:
        first = [r for r in runs if r["seed"] == args.seeds[0]]
        speeds = {r["name"]: r["throughput_qps"] for r in add_throughput(first, timing.throughput_queries)}
        runs = [{**r, "throughput_qps": speeds[r["name"]]} if r["seed"] == args.seeds[0] else r for r in runs]
        save(runs)
    for row in combine_seeds(runs):
        print(f"{row['name']:>18}  PSNR {row['psnr']:6.2f} (vs default {row['psnr_delta']:+.2f})  SSIM "
              f"{row['ssim']:.4f}  L_fre {row['lfre']:.3e}  step {row['step_ms'] or math.nan:6.1f} ms  "
              f"{row['bytes_per_material']:6d} B  {row['throughput_qps'] or math.nan:.3g} q/s")
    print(f"wrote {args.out / CHART_NAMES[kind]}.{{png,csv,json}}")
    return 0

