"""``frenbrdf select``: the smallest NBRDF/latent configuration that reaches a validation PSNR.

Candidates are the capacity variants (:func:`frenbrdf.evaluation.variants.capacity_variants`),
from the smallest material to the largest; they are read from a measured capacity front (JSON) or
trained and measured smallest first until one reaches the target.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from tqdm.auto import tqdm

from ..data.folders import list_materials
from ..io.atomic import save_json, write_text
from ..io.jsonfile import read_json
from ..io.outputs import OutputFolder
from ..training import TrainConfig
from ..training.config import config_from_dict
from .variants import MeasureSettings, SweepCaches, Variant, base_config, capacity_variants, run_variant, storage


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
    summary: dict
    """What ``OUT/selection.json`` holds."""


def by_size(rows: list[dict]) -> list[dict]:
    """Rows from the smallest material to the largest: NBRDF bytes, then latent bytes."""
    return sorted(rows, key=lambda r: (r["bytes_per_material"], r["latent_bytes"]))


def read_front(path: str | os.PathLike) -> dict:
    """A measured capacity front (JSON rows of configurations and their validation PSNR), checked."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"front file {path} does not exist")
    chart = read_json(path, "capacity front")
    if chart.get("chart") != "capacity" or not isinstance(chart.get("rows"), list):
        raise ValueError(f"{path}: not a capacity front; make one with research/charts/chart_capacity.py")
    needed = ("name", "psnr", "bytes_per_material", "latent_bytes", "config")
    for i, row in enumerate(chart["rows"]):
        missing = [k for k in needed if not isinstance(row, dict) or k not in row]
        if missing:
            raise ValueError(f"{path}: row {i} lacks {missing}")
        psnr = row["psnr"]
        if isinstance(psnr, bool) or not isinstance(psnr, (int, float)) or not math.isfinite(psnr):
            raise ValueError(f"{path}: row {i} ({row['name']!r:.40}) has no valid PSNR: {row['psnr']!r:.40}")
        for key in ("bytes_per_material", "latent_bytes"):
            if isinstance(row[key], bool) or not isinstance(row[key], int) or row[key] < 0:
                raise ValueError(f"{path}: row {i}: {key} must be a whole number ≥ 0, got {row[key]!r:.40}")
        if not isinstance(row["name"], str) or not isinstance(row["config"], dict):
            raise ValueError(f"{path}: row {i}: name must be a string and config a JSON object (a training config)")
        config_from_dict(dict(row["config"]), f"{path}: row {i}'s config")  # what select writes, train must read
    if not chart["rows"]:
        raise ValueError(f"{path}: holds no measured configuration")
    return chart


#: What ``select`` writes into its folder: the trained candidates and their cache (reused by a rerun) and the reports.
SELECT_FILES = ("runs", "cache", "config.json", "selection.json", "selection.md")


def select_config(data, target_psnr: float, out, *, front=None, base: TrainConfig | None = None,
                  variants: list[Variant] | None = None, measure: MeasureSettings | None = None,
                  progress: bool = True, overwrite: bool = False) -> Selection:
    """The smallest capacity configuration whose validation render PSNR reaches ``target_psnr``.

    Candidates go from the smallest material (NBRDF bytes, then latent bytes) to the
    largest. With ``front`` (a measured capacity front, :func:`read_front`) the measured rows decide, nothing is trained;
    without it each candidate (``variants``, default :func:`capacity_variants`, over
    ``base``, default :func:`base_config`) is trained and measured in ``OUT/runs/`` in that
    order until one reaches the target. If one does, ``OUT/config.json`` holds its
    training config (usable by ``frenbrdf train --config``; ``out`` set to ``OUT/run``).
    Either way ``OUT/selection.{json,md}`` report what was considered. ``OUT`` follows the output rule of
    :mod:`frenbrdf.io.outputs` (an earlier selection's folder is reused: its trained candidates are resumed).
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
    folder = OutputFolder.claim(out, command="select", inputs=[data, *([front] if front is not None else [])],
                                overwrite=overwrite)
    out = folder.begin(SELECT_FILES, keep=("runs", "cache"))  # trained candidates are resumed

    if chart is not None:
        considered = by_size(chart["rows"])
        source = f"measured chart {front} (data {chart.get('data', '?')}, {chart.get('epochs', '?')} epochs)"
        chosen = next((r for r in considered if r["psnr"] >= target), None)
    else:
        base = base or base_config(data)
        base.data = str(data)
        variants = variants if variants is not None else capacity_variants()
        measure = measure or MeasureSettings(lfre=False, progress=progress)
        order = sorted(variants, key=lambda v: (storage(v.config(base))["bytes_per_material"],
                                                storage(v.config(base))["latent_bytes"]))
        source = f"trained in {out / 'runs'} ({base.epochs} epochs each)"
        considered, chosen, caches = [], None, SweepCaches()
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
    folder.finish()
    return Selection(target, chosen is not None, chosen, best, considered, source, config_path, report_path, summary)


def _brief(row: dict) -> dict:
    keys = ("name", "hidden", "nbrdf_weights", "bytes_per_material", "latent", "latent_bytes", "psnr", "ssim",
            "delta_e", "lfre", "throughput_qps", "run")
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

