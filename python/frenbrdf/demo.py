"""The main job: data → FreNBRDF and both baselines → evaluation → a report folder.

``frenbrdf demo`` runs it. Without ``--data`` it first writes the default bank of 100
analytic materials. Training uses the ``demo`` training length of :mod:`frenbrdf.presets` so the
whole job takes about 8 minutes on 2 CPU cores; the report says what was run. The report folder
follows the output rule of :mod:`frenbrdf.io.outputs`: an earlier demo's folder is reused (its bank too).
"""

from __future__ import annotations

import dataclasses
import json
import platform
import time
from pathlib import Path
from typing import Any

import torch

from ._native import __version__
from .evaluation.evaluate import EvaluateConfig, evaluate_runs, report_markdown
from .io.atomic import write_text
from .io.outputs import OutputFolder
from .presets import TRAINING, method_names
from .training import Run, config_for, train

#: Evaluation settings of the demo: the full reconstruction table, a shorter editing table, and the rows of test-time
#: refinement of z (what ``frenbrdf reconstruct`` gives a user) beside the encoder-only ones (the paper's protocol).
DEMO_EVALUATION = EvaluateConfig(samples=4000, edits=120, edit_resolution=96, refine="latent")


def run_demo(out: str | Path = "frenbrdf-demo", data: str | Path | None = None, *, epochs: int | None = None,
             augmentation: str = "augmented", progress: bool = True, overwrite: bool = False) -> Path:
    """Runs the main job; returns the report folder. ``augmentation``: a
    :data:`frenbrdf.presets.AUGMENTATION` entry, the same for every method. ``overwrite``: write into a folder
    holding other entries (they are kept)."""
    folder = OutputFolder.claim(out, command="demo", inputs=[data] if data is not None else [], overwrite=overwrite)
    out = folder.begin(["runs", "cache", "evaluation", "README.md", *(["data"] if data is None else [])],
                       keep=["data", "cache"])  # an earlier demo's bank and coefficients are reused
    timings: dict[str, float] = {}
    start = time.perf_counter()
    if data is None:
        from .data.synth import write_bank

        data = out / "data"
        if not (data / "bank.json").exists():  # a complete bank from an earlier run is reused
            write_bank(data, n=100, seed=0, progress=progress)
        timings["synthesise 100 materials"] = time.perf_counter() - start
    runs = []
    for method in method_names():
        begin = time.perf_counter()
        # The report folder holds everything the demo made, the coefficient cache too.
        overrides: dict[str, Any] = {"epochs": epochs} if epochs is not None else {}
        cfg = config_for(method, training="demo", augmentation=augmentation, data=str(data), out=str(out / "runs" / method),
                         cache_dir=str(out / "cache"), progress=progress, **overrides)
        runs.append(train(cfg, overwrite=True))  # the demo folder is its own: a rerun trains afresh
        timings[f"train {method}"] = time.perf_counter() - begin
    begin = time.perf_counter()
    report = evaluate_runs([run.path for run in runs], out / "evaluation", config=dataclasses.replace(DEMO_EVALUATION, progress=progress))
    timings["evaluate"] = time.perf_counter() - begin
    timings["total"] = time.perf_counter() - start
    _write_readme(out, data, runs, report, timings)
    folder.finish()
    return folder.path


def _write_readme(out: Path, data, runs: list[Run], report: dict, timings: dict) -> None:
    table = report_markdown(report)
    lines = [
        "# frenbrdf demo report", "",
        f"frenbrdf {__version__}, torch {torch.__version__}, Python {platform.python_version()}, "
        f"{torch.get_num_threads()} torch threads.", "",
        "## What was run", "",
        f"- Data: `{data}` ({len(report['test_materials'])} test materials of a 70/10/20 split, seed "
        f"{runs[0].config.seed}).",
        f"- Training: FreNBRDF, NBRDF (η = 0) and HyperBRDF settings, each with {json.dumps(TRAINING['demo'])} over "
        "its preset: the same number of optimisation steps for every method, each at its own learning rate "
        "(HyperBRDF's 5e-5 is tuned for far longer training, so its row is undertrained here); augmentation "
        f"`{runs[0].config.augment.preset}` (docs/data.md). Run folders: "
        + ", ".join(f"`{r.path}`" for r in runs) + ".",
        f"- Evaluation: encoder given {DEMO_EVALUATION.samples} samples per test material, "
        f"{DEMO_EVALUATION.edits} interpolations for editing (renders {DEMO_EVALUATION.resolution}² and "
        f"{DEMO_EVALUATION.edit_resolution}²)"
        + (f"; each material also refined at test time on the same samples (`--refine {DEMO_EVALUATION.refine}`: "
           "the \"refined\" rows)." if DEMO_EVALUATION.refine != "none" else "."), "",
        "## Results", "", table, "",
        "**One seed: this ranking is within noise.** Training noise between seeds is as large as the "
        "differences between the methods here (about ±1 dB of PSNR); only a comparison over several seeds "
        "with intervals that exclude 0 decides (`frenbrdf train --seeds 0 1 2`, then `frenbrdf evaluate` on "
        "all the runs; the README's result tables are made so).", "",
        "The paper's columns come from its own protocol on measured MERL data with far longer training; "
        "this demo trains for minutes on analytic materials, so compare the methods with each other, not "
        "with the paper.", "",
        "![renders](evaluation/renders.png)", "", "![interpolation](evaluation/interpolation.png)", "",
        "![histograms](evaluation/histograms.png)", "",
        "## Time", "", "| step | seconds |", "|---|---|",
        *(f"| {step} | {seconds:.0f} |" for step, seconds in timings.items()), "",
    ]
    write_text(out / "README.md", "\n".join(lines))
