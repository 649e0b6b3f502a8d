"""Sweeps of training configurations: the frequency-loss and capacity charts, and ``select``.

A sweep trains a list of :class:`Variant` s — the FreNBRDF preset with a few keys
overridden, all on the same data, seed and split, with the same short training — and
measures each one:

- on the **validation** split: encode each material from 4000 samples, decode, render,
  compare with the render of the true table (PSNR, SSIM, RMSE; the code of
  :func:`frenbrdf.evaluation.reconstruction_rows`) and L_fre, always computed with the
  default :class:`~frenbrdf.losses.FrequencyLossConfig` so that variants compare;
- the training-step time (:func:`time_training_step`, the machinery of
  ``benches/train_step.py``), with and without the frequency term;
- the decoded NBRDF's evaluation throughput (queries/s, CPU, one thread; all variants
  timed in turn, :func:`add_throughput`) and the bytes a material costs: NBRDF weights × 4
  (float32) and the latent × 4.

A sweep may be repeated with other seeds (each seed its own split): :func:`combine_seeds`
averages a variant over them and compares it with the default of the same seed, whose
spread over the seeds shows how much a single training run varies.

Every run lives in ``WORK/runs/<name>-<key>/`` (``key``: a hash of the run's config) with
its measurements in ``result.json``; a sweep started again skips variants that hold one
and resumes interrupted training, so sweeps can be stopped and restarted at will, and the
two charts share the runs they have in common (the default configuration).

- Chart 2 (:func:`frequency_variants`): one-at-a-time variation of L_fre's lmax, number
  of θ_h slices, k and σ around the default.
- Chart 3 (:func:`capacity_variants`): NBRDF hidden sizes and latent sizes around the
  default, with the Pareto front of PSNR against bytes per material (:func:`pareto_front`).
- :func:`select_config`: the smallest chart-3 configuration that reaches a validation
  PSNR, from a measured chart or by training candidates smallest first
  (``frenbrdf select``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import statistics
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from .atomic import save_csv, save_json, write_text
from .data import list_materials, split_materials
from .evaluation import FrequencyMetric, reconstruction_rows
from .losses import FrequencyLoss
from .models.autoencoder import AutoEncoder, Model
from .models.nbrdf import N_INPUTS, NBRDF
from .render import save_figure
from .training import TrainConfig, _Distributed, _merge, _prepare, config_for, from_dict, loss_terms, to_dict, train

#: Training of every sweep run: the demo's short training (``frenbrdf.demo.DEMO_TRAINING``) with half its epochs,
#: so that the 15 runs of charts 2 and 3 take about 25 minutes per seed on one CPU thread.
SWEEP_TRAINING = {"epochs": 50, "batch_materials": 8, "context_samples": 2000, "query_samples": 2000}
#: File names of the charts in the output folder (``.png``, ``.csv``, ``.json``).
CHART_NAMES = {"frequency": "chart2_frequency", "capacity": "chart3_capacity"}


# --------------------------------------------------------------------------- variants


@dataclass
class Variant:
    """One configuration of a sweep: the base config with ``overrides`` (nested TrainConfig keys)."""

    name: str
    """Short label, e.g. ``"lmax=24"``; also names the run folder."""
    axis: str
    """The varied setting (``"lmax"``, ``"slices"``, ``"k"``, ``"sigma"``, ``"hidden"``, ``"latent"``),
    or ``"default"``."""
    value: object
    """Its value (for ``"default"``: None)."""
    overrides: dict = field(default_factory=dict)

    def config(self, base: TrainConfig) -> TrainConfig:
        """``base`` with the overrides applied (validated like any config)."""
        return from_dict(TrainConfig, _merge(to_dict(base), self.overrides), f"variant {self.name}")


def spread_slices(n: int) -> tuple[int, ...]:
    """``n`` θ_h bin indices spread evenly over 0 … 95: 4 → (0, 24, 48, 72), the default."""
    if not 1 <= n <= 90:
        raise ValueError(f"the number of slices must be in 1 … 90, got {n}")
    return tuple(i * 96 // n for i in range(n))


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


def capacity_variants(hidden=((21, 21), (48, 48), (60, 60, 60), (60, 60, 60, 60)), latent=(16, 64)) -> list[Variant]:
    """Chart 3: the default, then the NBRDF's hidden sizes and the latent size varied one at a time."""
    variants = [Variant("default", "default", None)]
    variants += [Variant("hidden=" + "x".join(map(str, h)), "hidden", list(h),
                         {"model": {"nbrdf": {"hidden": list(h)}}}) for h in hidden]
    variants += [Variant(f"latent={v}", "latent", v, {"model": {"encoder": {"latent": v}}}) for v in latent]
    return variants


def base_config(data, *, epochs: int | None = None, seed: int = 0) -> TrainConfig:
    """The FreNBRDF preset with the sweeps' short training (:data:`SWEEP_TRAINING`)."""
    overrides = {**SWEEP_TRAINING, **({"epochs": epochs} if epochs is not None else {})}
    return config_for("frenbrdf", data=str(data), seed=seed, **overrides)


def config_key(cfg: TrainConfig) -> str:
    """A short hash of what determines a run's result (not where it is written or shown)."""
    settings = to_dict(cfg)
    for name in ("out", "progress", "cache_dir", "device"):
        settings.pop(name)
    return hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()[:10]


def storage(cfg: TrainConfig) -> dict:
    """Bytes a material costs under a config: its NBRDF (float32 weights) and its latent."""
    weights = cfg.model.nbrdf.n_weights
    return {"nbrdf_weights": weights, "bytes_per_material": 4 * weights, "latent": cfg.model.encoder.latent,
            "latent_bytes": 4 * cfg.model.encoder.latent}


# --------------------------------------------------------------------------- measurements


def timed_seconds(functions: dict, steps: int, device: torch.device, *, warmup: int = 3,
                  statistic=statistics.median) -> dict[str, float]:
    """Time of each function over ``steps`` calls (median by default; ``statistic=min`` resists load from other
    processes), calls interleaved so that drift affects all alike."""
    times: dict[str, list[float]] = {name: [] for name in functions}
    for i in range(steps + warmup):
        for name, function in functions.items():
            if device.type == "cuda":
                torch.cuda.synchronize()
            start = time.perf_counter()
            function()
            if device.type == "cuda":
                torch.cuda.synchronize()
            if i >= warmup:
                times[name].append(time.perf_counter() - start)
    return {name: statistic(values) for name, values in times.items()}


def time_training_step(cfg: TrainConfig, steps: int = 30, device: torch.device | str = "cpu", *,
                       data_cache: dict | None = None, statistic=statistics.median) -> dict:
    """Time (median of ``steps``, or ``statistic``) of one optimisation step of ``cfg`` on a batch of
    ``cfg.data``'s training materials.

    With L_fre (η > 0) it also times the same step without the frequency term (same model,
    same samples), so the difference is what L_fre adds, and the parts of L_fre alone.
    ``cfg.data`` needs only ``cfg.batch_materials`` training materials; ``data_cache`` as in
    :func:`frenbrdf.training.train`.
    """
    device = torch.device(device)
    files = {path.stem: path for path in list_materials(cfg.data)}
    split = split_materials(files, cfg.seed, cfg.split)
    _, bank, truth = _prepare(cfg, split, files, _Distributed(), data_cache)
    torch.manual_seed(0)
    network = AutoEncoder(cfg.model).to(device)
    frequency = FrequencyLoss(cfg.loss.frequency).to(device)
    optimizer = torch.optim.Adam(network.parameters(), lr=cfg.lr)
    generator = torch.Generator().manual_seed(0)
    batch = list(range(min(cfg.batch_materials, len(split.train))))
    context = bank.sample(batch, cfg.context_samples, generator).to(device)
    query = bank.sample(batch, cfg.query_samples, generator).to(device)
    true = truth[batch].to(device) if truth is not None else None

    def step(with_frequency: bool):
        terms = loss_terms(network, frequency if with_frequency else None, cfg.loss, context, query,
                           true if with_frequency else None)
        optimizer.zero_grad(set_to_none=True)
        terms.total.backward()
        optimizer.step()

    result = {"method": cfg.method, "nbrdf_hidden": list(cfg.model.nbrdf.hidden), "batch_materials": len(batch),
              "samples": [cfg.context_samples, cfg.query_samples], "eta": cfg.loss.eta}
    if cfg.loss.eta == 0:
        result["step_s"] = timed_seconds({"step": lambda: step(False)}, steps, device, statistic=statistic)["step"]
        return result
    params = [p.detach().requires_grad_() for p in network(context.encoder_input())[1]]
    timed = timed_seconds({"step": lambda: step(True), "without": lambda: step(False),
                           "nbrdf_eval": lambda: frequency.predicted_maps(params),
                           "fre": lambda: frequency(params, true).backward()}, steps, device, statistic=statistic)
    result.update(step_s=timed["step"], step_without_fre_s=timed["without"],
                  fre_added_share=timed["step"] / timed["without"] - 1,
                  fre_nbrdf_eval_s=timed["nbrdf_eval"], fre_forward_backward_s=timed["fre"])
    return result


def nbrdf_throughput(nbrdfs: dict[str, NBRDF], queries: int = 1 << 18, repeats: int = 40,
                     threads: int = 1) -> dict[str, float]:
    """Queries per second of :meth:`NBRDF.mapped` (one material each, CPU) on ``threads`` torch threads.

    The NBRDFs are timed in turn, round after round, and each counts its fastest of
    ``repeats`` calls: the one least disturbed by other processes.
    """
    coords = np.random.default_rng(0).uniform(-1, 1, (queries, N_INPUTS)).astype(np.float32)
    previous = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        seconds = timed_seconds({name: (lambda nbrdf=nbrdf: nbrdf.mapped(coords)) for name, nbrdf in nbrdfs.items()},
                                repeats, torch.device("cpu"), warmup=2, statistic=min)
    finally:
        torch.set_num_threads(previous)
    return {name: queries / value for name, value in seconds.items()}


def add_throughput(rows: list[dict], queries: int = 1 << 18, repeats: int = 40) -> list[dict]:
    """Sets ``throughput_qps`` of each row, its run's decoded NBRDF timed with all the others'."""
    nbrdfs = {}
    for row in rows:
        model = Model.load(row["run"])
        nbrdfs[row["name"]] = model.decode(np.zeros(model.config.encoder.latent))  # the values do not change speed
    speeds = nbrdf_throughput(nbrdfs, queries, repeats)
    return [{**row, "throughput_qps": speeds[row["name"]]} for row in rows]


@dataclass
class MeasureSettings:
    """What a sweep measures on each trained variant, and how."""

    samples: int = 4000
    """Samples given to the encoder per validation material."""
    resolution: int = 256
    """Render size of the validation renders."""
    seed: int = 0
    """Seeds the encoder's samples."""
    timing_steps: int = 20
    """Training steps timed per variant (0: no step timing); the fastest counts (least disturbed by other
    processes; ``benches/train_step.py`` reports the median)."""
    timing_materials: int = 16
    """Materials of the data folder the step timing reads (enough for one batch)."""
    throughput_queries: int = 1 << 18
    """Queries of the throughput measurement (chart 3, :func:`add_throughput`; 0: not measured)."""
    lfre: bool = True
    """Measure L_fre on validation (``select`` needs only the PSNR)."""
    progress: bool = True


class _Caches:
    """What a sweep keeps between runs: the mapped materials of training and of timing, the metric."""

    def __init__(self):
        self.train: dict = {}
        self.timing: dict = {}
        self._metric: FrequencyMetric | None = None

    @property
    def metric(self) -> FrequencyMetric:
        if self._metric is None:
            self._metric = FrequencyMetric()
        return self._metric


def _timing_data(data: Path, work: Path, n: int) -> Path:
    """A folder linking the first ``n`` materials of ``data``: enough for one timed batch, fast to read."""
    folder = work / "timing-data"
    folder.mkdir(parents=True, exist_ok=True)
    wanted = {path.name: path.resolve() for path in list_materials(data)[:n]}
    for link in folder.glob("*.binary"):
        if link.name not in wanted or link.resolve() != wanted[link.name]:
            link.unlink()
    for name, target in wanted.items():
        if not (folder / name).exists():
            (folder / name).symlink_to(target)
    return folder


SUMMARY_KEYS = ("psnr", "ssim", "rmse", "lfre")


def run_variant(variant: Variant, base: TrainConfig, work: str | os.PathLike,
                measure: MeasureSettings = MeasureSettings(), caches: _Caches | None = None) -> dict:
    """Trains one variant (or resumes it) in ``WORK/runs/`` and measures it; returns its result row."""
    work = Path(work)
    caches = caches or _Caches()
    cfg = variant.config(base)
    key = config_key(cfg)
    run_dir = work / "runs" / f"{variant.name.replace('=', '-')}-{key}"
    result_path = run_dir / "result.json"
    if result_path.exists():
        try:
            row = json.loads(result_path.read_text())
            if row.get("key") == key and (not measure.timing_steps or "step_ms" in row) and (
                    not measure.lfre or row.get("lfre") is not None):
                return {**row, "name": variant.name, "axis": variant.axis, "value": variant.value, "seed": cfg.seed}
        except json.JSONDecodeError:
            pass  # a damaged result is measured again
    cfg.out, cfg.progress = str(run_dir), measure.progress
    cfg.cache_dir = cfg.cache_dir or str(work / "cache")
    resume = (run_dir / "last.pt").exists()
    start = time.perf_counter()
    result = train(cfg, resume=resume, data_cache=caches.train)
    train_seconds = time.perf_counter() - start

    model = Model.load(run_dir)
    files = {path.stem: path for path in list_materials(cfg.data)}
    split = json.loads((run_dir / "split.json").read_text())
    validation = [files[name] for name in sorted(split["val"])]
    begin = time.perf_counter()
    per_material = reconstruction_rows(model, validation, samples=measure.samples, resolution=measure.resolution,
                                       seed=measure.seed, frequency_metric=caches.metric if measure.lfre else False,
                                       progress=measure.progress)
    best = next(epoch for epoch in result.history if epoch["epoch"] == result.best_epoch)
    frequency = cfg.loss.frequency
    row = {"name": variant.name, "axis": variant.axis, "value": variant.value, "seed": cfg.seed, "key": key,
           "run": str(run_dir),
           "hidden": list(cfg.model.nbrdf.hidden), **storage(cfg),
           "lmax": frequency.lmax, "n_slices": len(frequency.slices), "slices": list(frequency.slices),
           "k": frequency.k, "sigma": frequency.sigma,
           **{name: float(np.mean([r[name] for r in per_material])) if name in per_material[0] else None
              for name in SUMMARY_KEYS},
           "psnr_std": float(np.std([r["psnr"] for r in per_material])),
           "val_materials": len(per_material), "best_epoch": result.best_epoch, "val_rec": best["val_rec"],
           "val_fre": best.get("val_fre"), "train_s": round(train_seconds, 1), "resumed": resume,
           "measure_s": None, "per_material": per_material, "config": to_dict(cfg)}
    if measure.timing_steps:
        timing_cfg = variant.config(base)
        timing_cfg.data = str(_timing_data(Path(cfg.data), work, measure.timing_materials))
        timing_cfg.cache_dir, timing_cfg.progress = cfg.cache_dir, False
        timed = time_training_step(timing_cfg, measure.timing_steps, data_cache=caches.timing, statistic=min)
        row.update(step_ms=1e3 * timed["step_s"], step_without_fre_ms=1e3 * timed.get("step_without_fre_s", math.nan),
                   fre_share=timed.get("fre_added_share", math.nan), timing_threads=torch.get_num_threads())
    row["measure_s"] = round(time.perf_counter() - begin, 1)
    save_json(result_path, row)
    return row


def run_sweep(variants: list[Variant], base: TrainConfig, work: str | os.PathLike,
              measure: MeasureSettings = MeasureSettings(), *, on_row=None) -> list[dict]:
    """Runs (or skips, when measured already) every variant in order; ``on_row(rows)`` after each."""
    caches, rows = _Caches(), []
    names = [v.name for v in variants]
    if len(set(names)) != len(names):
        raise ValueError(f"variant names must be distinct, got {names}")
    for variant in tqdm(variants, desc="sweep", disable=not measure.progress):
        rows.append(run_variant(variant, base, work, measure, caches))
        if on_row is not None:
            on_row(rows)
    return rows


# --------------------------------------------------------------------------- charts


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
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    runs = [{"seed": 0, **run} for run in runs]
    rows = combine_seeds(runs)
    if kind == "capacity":
        for row, on_front in zip(rows, pareto_front(rows)):
            row["front"] = on_front
    stem = out / CHART_NAMES[kind]
    paths = {"json": stem.with_suffix(".json"), "csv": stem.with_suffix(".csv"), "png": stem.with_suffix(".png")}
    save_json(paths["json"], {"chart": kind, **(meta or {}), "rows": rows, "runs": runs})
    save_csv(paths["csv"], _csv_rows(rows))
    (_plot_frequency if kind == "frequency" else _plot_capacity)(rows, paths["png"], meta or {})
    return paths


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


FREQUENCY_AXES = (("lmax", "lmax", "L_fre band limit lmax"), ("slices", "n_slices", "θ_h slices"),
                  ("k", "k", "kNN neighbours k"), ("sigma", "sigma", "kNN width σ"))


def _axis_points(rows: list[dict], axis: str, column: str) -> list[dict]:
    """The rows varying ``axis`` plus the default, sorted by the varied value."""
    points = [r for r in rows if r["axis"] in (axis, "default")]
    return sorted(points, key=lambda r: r[column])


def _plot_frequency(rows: list[dict], path: Path, meta: dict) -> None:
    plt = _pyplot()
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
            for xi, p in zip(x, points):
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
    save_figure(figure, path, dpi=110)
    plt.close(figure)


def _label(row: dict) -> str:
    return f"6→{'→'.join(map(str, row['hidden']))}→3, z{row['latent']}"


def _plot_capacity(rows: list[dict], path: Path, meta: dict) -> None:
    plt = _pyplot()
    panels = (("bytes_per_material", "psnr", "bytes per material (NBRDF float32 weights)", "validation PSNR (dB)"),
              ("throughput_mqps", "psnr", "NBRDF evaluation throughput (million queries/s, 1 CPU thread)",
               "validation PSNR (dB)"),
              ("bytes_per_material", "ssim", "bytes per material", "validation SSIM"),
              ("bytes_per_material", "lfre", "bytes per material", "validation L_fre"))
    rows = [{**r, "throughput_mqps": r["throughput_qps"] / 1e6} if _present(r.get("throughput_qps")) else r
            for r in rows]
    figure, axes = plt.subplots(2, 2, figsize=(12, 9), squeeze=False)
    colours = {16: "#55a868", 40: "#4c72b0", 64: "#c44e52"}
    for ax, (x_key, y_key, x_label, y_label) in zip(axes.flat, panels):
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
                front = [r for r, on in zip(rows, pareto_front(rows, maximise=("psnr", x_key), minimise=())) if on]
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
    save_figure(figure, path, dpi=110)
    plt.close(figure)


def chart_main(kind: str, argv: list[str] | None = None, doc: str | None = None) -> int:
    """Command line of ``benches/chart_{frequency,capacity}.py``: sweep (resumable), then write the chart."""
    import argparse

    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", required=True, type=Path, help="folder of MERL files")
    parser.add_argument("--out", type=Path, default=Path("docs/charts"), help="chart folder (default docs/charts)")
    parser.add_argument("--work", type=Path, default=Path("bench-results/sweeps"),
                        help="run folders, shared by the charts and kept for resuming (default bench-results/sweeps)")
    parser.add_argument("--epochs", type=int, default=SWEEP_TRAINING["epochs"],
                        help=f"training epochs per run (default {SWEEP_TRAINING['epochs']})")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0],
                        help="training seeds (default 0); each fixes its own split, and a variant's PSNR is also "
                        "given against the default of the same seed; step times are measured on the first")
    parser.add_argument("--threads", type=int, default=1, help="torch threads for training and timing (default 1)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    variants = frequency_variants() if kind == "frequency" else capacity_variants()
    measure = MeasureSettings(timing_steps=20, progress=not args.quiet)
    start = time.perf_counter()
    base = base_config(args.data, epochs=args.epochs, seed=args.seeds[0])
    seeds = ", ".join(map(str, args.seeds))
    meta = {"data": str(args.data), "epochs": base.epochs, "seeds": args.seeds, "torch_threads": args.threads,
            "training": {k: getattr(base, k) for k in SWEEP_TRAINING},
            "measure": {k: v for k, v in vars(measure).items() if k != "progress"},
            "caption": f"{base.epochs} epochs each, {Path(args.data).name}, validation split, seed(s) {seeds}."}

    def save(runs):  # after every variant: a partial chart is there to look at while the sweep runs
        save_chart(kind, runs, args.out, {**meta, "sweep_s": round(time.perf_counter() - start, 1)})

    runs: list[dict] = []
    for i, seed in enumerate(args.seeds):
        base = base_config(args.data, epochs=args.epochs, seed=seed)
        # Step time does not depend on the seed: timed on the first only.
        seed_measure = measure if i == 0 else dataclasses.replace(measure, timing_steps=0)
        runs += run_sweep(variants, base, args.work, seed_measure, on_row=lambda done, before=list(runs): save(
            before + done))
    if kind == "capacity" and measure.throughput_queries:
        first = [r for r in runs if r["seed"] == args.seeds[0]]
        speeds = {r["name"]: r["throughput_qps"] for r in add_throughput(first, measure.throughput_queries)}
        runs = [{**r, "throughput_qps": speeds[r["name"]]} if r["seed"] == args.seeds[0] else r for r in runs]
        save(runs)
    for row in combine_seeds(runs):
        print(f"{row['name']:>18}  PSNR {row['psnr']:6.2f} (vs default {row['psnr_delta']:+.2f})  SSIM "
              f"{row['ssim']:.4f}  L_fre {row['lfre']:.3e}  step {row['step_ms'] or math.nan:6.1f} ms  "
              f"{row['bytes_per_material']:6d} B  {row['throughput_qps'] or math.nan:.3g} q/s")
    print(f"wrote {args.out / CHART_NAMES[kind]}.{{png,csv,json}}")
    return 0


# --------------------------------------------------------------------------- select


@dataclass
class Selection:
    """What :func:`select_config` found."""

    target_psnr: float
    reached: bool
    chosen: dict | None
    """The chosen row (the smallest configuration reaching the target), or None."""
    best: dict | None
    """The row of highest PSNR among those considered."""
    considered: list[dict]
    """Rows considered, smallest first (with ``--front``: all measured; else: those trained)."""
    source: str
    config_path: Path | None
    report_path: Path


def by_size(rows: list[dict]) -> list[dict]:
    """Rows from the smallest material to the largest: NBRDF bytes, then latent bytes."""
    return sorted(rows, key=lambda r: (r["bytes_per_material"], r["latent_bytes"]))


def read_front(path: str | os.PathLike) -> dict:
    """A chart-3 JSON (``chart3_capacity.json``), checked."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"front file {path} does not exist")
    try:
        chart = json.loads(path.read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    if not isinstance(chart, dict) or chart.get("chart") != "capacity" or not isinstance(chart.get("rows"), list):
        raise ValueError(f"{path}: not a chart-3 (capacity) file; make one with benches/chart_capacity.py")
    needed = ("name", "psnr", "bytes_per_material", "latent_bytes", "config")
    for i, row in enumerate(chart["rows"]):
        missing = [k for k in needed if not isinstance(row, dict) or k not in row]
        if missing:
            raise ValueError(f"{path}: row {i} lacks {missing}")
        if not isinstance(row["psnr"], (int, float)) or math.isnan(row["psnr"]):
            raise ValueError(f"{path}: row {i} ({row['name']}) has no valid PSNR: {row['psnr']!r}")
    if not chart["rows"]:
        raise ValueError(f"{path}: holds no measured configuration")
    return chart


def select_config(data, target_psnr: float, out, *, front=None, base: TrainConfig | None = None,
                  variants: list[Variant] | None = None, measure: MeasureSettings | None = None,
                  progress: bool = True) -> Selection:
    """The smallest chart-3 configuration whose validation render PSNR reaches ``target_psnr``.

    Candidates go from the smallest material (NBRDF bytes, then latent bytes) to the
    largest. With ``front`` (a chart-3 JSON) the measured rows decide, nothing is trained;
    without it each candidate (``variants``, default :func:`capacity_variants`, over
    ``base``, default :func:`base_config`) is trained and measured in ``OUT/runs/`` in that
    order until one reaches the target. If one does, ``OUT/config.json`` holds its
    training config (usable by ``frenbrdf train --config``; ``out`` set to ``OUT/run``).
    Either way ``OUT/selection.{json,md}`` report what was considered.
    """
    try:
        target = float(target_psnr)
    except (TypeError, ValueError):
        raise ValueError(f"target PSNR must be a number of dB, got {target_psnr!r}") from None
    if not (math.isfinite(target) and target > 0):
        raise ValueError(f"target PSNR must be a finite positive number of dB, got {target_psnr}")
    data = Path(data)
    list_materials(data)  # the data folder exists and holds materials
    if front is not None and (base is not None or variants is not None):
        raise ValueError("a base config or candidates apply to training; with a front file nothing is trained")
    chart = read_front(front) if front is not None else None  # a bad file fails before anything is written
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)

    if chart is not None:
        considered = by_size(chart["rows"])
        source = f"measured chart {front} (data {chart.get('data', '?')}, {chart.get('epochs', '?')} epochs)"
        chosen = next((r for r in considered if r["psnr"] >= target), None)
    else:
        base = base or base_config(data)
        base.data = str(data)
        variants = variants if variants is not None else capacity_variants()
        measure = measure or MeasureSettings(timing_steps=0, throughput_queries=0, lfre=False, progress=progress)
        order = sorted(variants, key=lambda v: (storage(v.config(base))["bytes_per_material"],
                                                storage(v.config(base))["latent_bytes"]))
        source = f"trained in {out / 'runs'} ({base.epochs} epochs each)"
        considered, chosen, caches = [], None, _Caches()
        for variant in tqdm(order, desc="select", disable=not progress):
            row = run_variant(variant, base, out, measure, caches)
            considered.append(row)
            if row["psnr"] >= target:
                chosen = row
                break
    best = max(considered, key=lambda r: r["psnr"]) if considered else None
    config_path = None
    if chosen is not None:
        config = dict(chosen["config"])
        config.update(data=str(data), out=str(out / "run"), cache_dir="", progress=True)
        config_path = out / "config.json"
        save_json(config_path, config)
    summary = {"target_psnr": target, "reached": chosen is not None, "source": source,
               "chosen": _brief(chosen) if chosen else None, "best": _brief(best) if best else None,
               "config": str(config_path) if config_path else None, "considered": [_brief(r) for r in considered]}
    save_json(out / "selection.json", summary)
    report_path = out / "selection.md"
    write_text(report_path, _selection_markdown(summary))
    return Selection(target, chosen is not None, chosen, best, considered, source, config_path, report_path)


def _brief(row: dict) -> dict:
    keys = ("name", "hidden", "nbrdf_weights", "bytes_per_material", "latent", "latent_bytes", "psnr", "ssim",
            "lfre", "throughput_qps", "run")
    return {k: row[k] for k in keys if k in row}


def _selection_markdown(summary: dict) -> str:
    target = summary["target_psnr"]
    if summary["reached"]:
        c = summary["chosen"]
        verdict = (f"Chosen: **{c['name']}**, NBRDF 6→{'→'.join(map(str, c['hidden']))}→3 "
                   f"({c['bytes_per_material']} bytes per material), latent {c['latent']}: "
                   f"validation PSNR {c['psnr']:.2f} dB ≥ {target:g} dB. "
                   f"Config: `{summary['config']}` (`frenbrdf train --config {summary['config']}`).")
    else:
        b = summary["best"]
        verdict = (f"**No configuration reaches {target:g} dB.** The best is {b['name']} at {b['psnr']:.2f} dB."
                   if b else f"**No configuration reaches {target:g} dB.**")
    lines = [f"# frenbrdf select: target validation PSNR {target:g} dB", "", f"Candidates: {summary['source']}.", "",
             verdict, "", "| configuration | NBRDF | bytes/material | latent | PSNR (dB) | reaches |",
             "|---|---|---|---|---|---|"]
    for r in summary["considered"]:
        lines.append(f"| {r['name']} | 6→{'→'.join(map(str, r['hidden']))}→3 | {r['bytes_per_material']} | "
                     f"{r['latent']} | {r['psnr']:.2f} | {'yes' if r['psnr'] >= target else 'no'} |")
    return "\n".join(lines) + "\n"
