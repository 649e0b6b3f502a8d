"""Variants of the FreNBRDF preset, trained and measured: what ``select`` (and the research sweeps) run.

A :class:`Variant` is the FreNBRDF preset with a few keys overridden; all variants of a
sweep train on the same data, seed and split with the same short training (the ``sweep``
training length of :mod:`frenbrdf.presets`). :func:`run_variant` trains one (or resumes
it) and measures it:

- on the **validation** split: encode each material from 4000 samples, decode, render,
  compare with the render of the true table (PSNR, SSIM, RMSE, ΔE; the code of
  :func:`frenbrdf.render.scoring.reconstruction_rows`) and L_fre, always computed with the
  default :class:`~frenbrdf.models.losses.FrequencyLossConfig` so that variants compare;
- the bytes a material costs: NBRDF weights × 4 (float32) and the latent × 4.

Nothing here is timed: the research sweeps (``research/charts/sweeps.py``) time the training
steps and the decoded NBRDFs themselves, with ``benches/step_timing.py``.

Every run lives in ``WORK/runs/<name>-<key>/`` (``key``: a hash of the run's config) with
its measurements in ``result.json``; a sweep started again skips variants that hold one
and resumes interrupted training, so sweeps can be stopped and restarted at will.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from ..configs import from_dict, merge, to_dict
from ..data.folders import list_materials
from ..io.atomic import save_json
from ..io.jsonfile import read_json
from ..render.scoring import FrequencyMetric, reconstruction_rows
from ..training import TrainConfig, config_for, train


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
        return from_dict(TrainConfig, merge(to_dict(base), self.overrides, TrainConfig), f"variant {self.name}")


def capacity_variants(hidden=((21, 21), (48, 48), (60, 60, 60), (60, 60, 60, 60)), latent=(16, 64)) -> list[Variant]:
    """Chart 3: the default, then the NBRDF's hidden sizes and the latent size varied one at a time."""
    variants = [Variant("default", "default", None)]
    variants += [Variant("hidden=" + "x".join(map(str, h)), "hidden", list(h),
                         {"model": {"nbrdf": {"hidden": list(h)}}}) for h in hidden]
    variants += [Variant(f"latent={v}", "latent", v, {"model": {"encoder": {"latent": v}}}) for v in latent]
    return variants


def base_config(data, *, epochs: int | None = None, seed: int = 0) -> TrainConfig:
    """The FreNBRDF preset with the sweeps' short training (the ``sweep`` training length)."""
    overrides: dict[str, Any] = {"epochs": epochs} if epochs is not None else {}
    return config_for("frenbrdf", training="sweep", data=str(data), seed=seed, **overrides)


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


@dataclass
class MeasureSettings:
    """What a sweep measures on each trained variant, and how."""

    samples: int = 4000
    """Samples given to the encoder per validation material."""
    resolution: int = 256
    """Render size of the validation renders."""
    seed: int = 0
    """Seeds the encoder's samples."""
    lfre: bool = True
    """Measure L_fre on validation (``select`` needs only the PSNR)."""
    progress: bool = True


class SweepCaches:
    """What a sweep keeps between runs: the mapped materials of training, the metric."""

    def __init__(self):
        self.train: dict = {}
        self._metric: FrequencyMetric | None = None

    @property
    def metric(self) -> FrequencyMetric:
        if self._metric is None:
            self._metric = FrequencyMetric()
        return self._metric


SUMMARY_KEYS = ("psnr", "ssim", "rmse", "delta_e", "lfre")


def run_variant(variant: Variant, base: TrainConfig, work: str | os.PathLike,
                measure: MeasureSettings | None = None, caches: SweepCaches | None = None) -> dict:
    """Trains one variant (or resumes it) in ``WORK/runs/`` and measures it (default :class:`MeasureSettings`);
    returns its result row."""
    measure = MeasureSettings() if measure is None else measure
    work = Path(work)
    caches = caches or SweepCaches()
    cfg = variant.config(base)
    key = config_key(cfg)
    run_dir = work / "runs" / f"{variant.name.replace('=', '-')}-{key}"
    result_path = run_dir / "result.json"
    if result_path.exists():
        try:
            row = read_json(result_path, "result file")
            if row.get("key") == key and (not measure.lfre or row.get("lfre") is not None):
                return {**row, "name": variant.name, "axis": variant.axis, "value": variant.value, "seed": cfg.seed}
        except ValueError:
            pass  # a damaged result is measured again
    cfg.out, cfg.progress = str(run_dir), measure.progress
    cfg.cache_dir = cfg.cache_dir or str(work / "cache")
    resume = (run_dir / "last.pt").exists()
    start = time.perf_counter()
    run = train(cfg, resume=resume, overwrite=not resume, data_cache=caches.train)  # its own work folder
    train_seconds = time.perf_counter() - start

    model = run.model()
    files = {path.stem: path for path in list_materials(cfg.data)}
    validation = [files[name] for name in sorted(run.split.val)]
    begin = time.perf_counter()
    per_material = reconstruction_rows(model, validation, samples=measure.samples, resolution=measure.resolution,
                                       seed=measure.seed, frequency_metric=caches.metric if measure.lfre else False,
                                       progress=measure.progress)
    best = run.best
    frequency = cfg.loss.frequency
    row = {"name": variant.name, "axis": variant.axis, "value": variant.value, "seed": cfg.seed, "key": key,
           "run": str(run_dir),
           "hidden": list(cfg.model.nbrdf.hidden), **storage(cfg),
           "lmax": frequency.lmax, "n_slices": len(frequency.slices), "slices": list(frequency.slices),
           "k": frequency.k, "sigma": frequency.sigma,
           **{name: float(np.mean([r[name] for r in per_material])) if name in per_material[0] else None
              for name in SUMMARY_KEYS},
           "psnr_std": float(np.std([r["psnr"] for r in per_material])),
           "val_materials": len(per_material), "best_epoch": best["epoch"], "val_rec": best["val_rec"],
           "val_fre": best.get("val_fre"), "train_s": round(train_seconds, 1), "resumed": resume,
           "measure_s": None, "per_material": per_material, "config": to_dict(cfg)}
    row["measure_s"] = round(time.perf_counter() - begin, 1)
    save_json(result_path, row)
    return row


def run_sweep(variants: list[Variant], base: TrainConfig, work: str | os.PathLike,
              measure: MeasureSettings | None = None, *, on_row=None) -> list[dict]:
    """Runs (or skips, when measured already) every variant in order, measured as ``measure`` says (default
    :class:`MeasureSettings`); ``on_row(rows)`` after each."""
    measure = MeasureSettings() if measure is None else measure
    caches, rows = SweepCaches(), []
    names = [v.name for v in variants]
    if len(set(names)) != len(names):
        raise ValueError(f"variant names must be distinct, got {names}")
    for variant in tqdm(variants, desc="sweep", disable=not measure.progress):
        rows.append(run_variant(variant, base, work, measure, caches))
        if on_row is not None:
            on_row(rows)
    return rows

