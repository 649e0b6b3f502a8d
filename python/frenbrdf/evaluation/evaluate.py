"""Evaluation (docs/method.md §7): reconstruction and editing tables, histograms, render grids.

- Reconstruction: each test material is encoded from N random valid bins (default 4000,
  the same samples for every method; a measurement evaluated at them in a random order of each pair,
  :func:`frenbrdf.io.sampling.truth_samples`), decoded, rendered and compared with the render of the
  true table: RMSE, PSNR, SSIM (scikit-image, data_range 1) and the colour difference ΔE
  (CIEDE2000) over the lit material pixels (:func:`frenbrdf.render.material_mask`), PSNR and ΔE over
  the highlights (the 5 % brightest of those pixels in the truth's linear render,
  :func:`frenbrdf.render.scoring.highlight_mask`), and the frequency loss. With ``EvaluateConfig.refine`` the same samples are also refined at test time
  (:func:`frenbrdf.models.reconstruct.reconstruct`, what a user reconstructing a material runs) and the
  refined NBRDF measured the same way: the "refined" rows. With several sampling patterns
  (``EvaluateConfig.patterns``, :mod:`frenbrdf.io.patterns`: the devices imitated) each material is also encoded
  from the same number of pairs of each further pattern and measured the same way: rows ``<key>@<pattern>``, each
  pattern's rows its own in the tables; editing, the figures and the spectra use the first pattern's latents.
- Editing: each unordered pair (a, b) of test materials at most once and interior
  t ∈ {0.25, 0.5, 0.75}; the truth is
  the table (1 − t)·a + t·b (its render is the same blend of the linear renders, since
  rendering is linear in the BRDF), the prediction decode((1 − t)·z_a + t·z_b) of the encoder's
  latents (the paper's editing) and, with refinement, of the refined latents too.

``evaluate_runs`` does both for several runs side by side and writes Markdown, JSON and
PNG figures (:mod:`frenbrdf.render.figures`, and ``spectrum.png``: the evaluated materials' mean per-degree power
spectra and each method's error spectrum, :class:`frenbrdf.evaluation.spectrum.SpectrumSummary`); ``frenbrdf evaluate``
is its command line. The
materials are the runs' test split, or (``EvaluateConfig.all_materials``, ``--all``) every
material of a folder that no run trained or validated on: an out-of-distribution test.
"""

from __future__ import annotations

import dataclasses
import os
import time
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from ..data.folders import list_materials
from ..io.atomic import save_json, write_text
from ..io.formats import read_measured
from ..io.outputs import OutputFolder
from ..io.patterns import DEFAULT as DEFAULT_PATTERN
from ..io.patterns import PATTERNS, pattern_samples
from ..io.sampling import as_table
from ..models.autoencoder import Model
from ..models.reconstruct import BUDGETS, refine_config
from ..presets import method_names
from ..render.figures import FIGURE_FILES, drop_unshown_renders, rendered_materials, write_figures
from ..render.renderer import Scene, material_mask, render_linear, tonemap
from ..render.scoring import (
    FrequencyMetric as FrequencyMetric,  # re-exported: frenbrdf.evaluation.evaluate keeps its public names
)
from ..render.scoring import Scoring, highlight_mask
from ..render.scoring import image_metrics as image_metrics
from ..render.scoring import reconstruction_rows as reconstruction_rows
from ..training.run import Run
from .editing import edit_pairs as edit_pairs  # re-exported: frenbrdf.evaluation.evaluate keeps its public names
from .editing import edit_rows
from .spectrum import SpectrumSummary
from .statistics import REFERENCE, compare_seeds
from .tables import PAPER as PAPER  # re-exported: frenbrdf.evaluation.evaluate keeps its public names
from .tables import ROWS as ROWS
from .tables import colour_losses, pattern_suffix, report_markdown, seeds_markdown, summarise, table_rows
from .tables import markdown_table as markdown_table

#: The largest render sizes an evaluation takes. It holds the display renders of the eight materials ``renders.png``
#: can show (at 1024², with three runs refined, about 1.4 GB) and each material's linear render at the editing size
#: (1.6 MB a material at 256²).
MAX_RESOLUTION, MAX_EDIT_RESOLUTION = 1024, 256


@dataclass
class EvaluateConfig:
    """Settings of :func:`evaluate_runs`."""

    samples: int = 4000
    """Samples given to the encoder per test material."""
    edits: int = 2000
    """At most this many interpolations (pair, t) in the editing table: every unordered pair of test
    materials once, a random subset of the pairs when there are more."""
    weights: tuple[float, ...] = (0.25, 0.5, 0.75)
    """Interpolation weights t, interior only (t = 0 or 1 is a reconstruction, not an edit)."""
    seed: int = 0
    resolution: int = 256
    """Render size; the editing table may use ``edit_resolution``."""
    edit_resolution: int = 128
    """Render size of the editing table (thousands of renders)."""
    max_materials: int = 0
    """Evaluate at most this many materials, the first by name (0: all)."""
    all_materials: bool = False
    """Evaluate every material of the data folder that no run trained or validated on (out-of-distribution),
    instead of the runs' test split; needs the folder (``data``)."""
    refine: str = "none"
    """Test-time refinement, a budget name of :data:`frenbrdf.models.reconstruct.BUDGETS`: besides the encoder-only rows
    (the paper's protocol), each material is refined on the same samples and measured again ("none": not)."""
    patterns: tuple[str, ...] = (DEFAULT_PATTERN,)
    """The sampling patterns each material is encoded from (:data:`frenbrdf.io.patterns.PATTERNS`), ``samples``
    pairs of each: the first gives the rows under the plain keys, editing, the figures and the spectra; each other
    its rows ``<key>@<pattern>``. ``merl-bins`` draws from the evaluation's seed as it always has; another pattern
    from a seed of its own (the evaluation's and the name's), so adding a pattern changes no other's numbers."""
    progress: bool = True

    def __post_init__(self):
        if self.refine not in BUDGETS:
            raise ValueError(f"refine must be a refinement budget, one of {tuple(BUDGETS)}; got {self.refine!r}")
        self.patterns = tuple(self.patterns)
        unknown = [name for name in self.patterns if name not in PATTERNS]
        if not self.patterns or unknown or len(set(self.patterns)) != len(self.patterns):
            raise ValueError(f"patterns must be one or more distinct sampling patterns of {', '.join(PATTERNS)}; "
                             f"got {self.patterns!r}")
        # Every test material's editing truth is kept for the editing table, and each material's renders while it
        # is scored: the render sizes bound the memory an evaluation needs.
        for name, value, most in (("resolution", self.resolution, MAX_RESOLUTION),
                                  ("edit_resolution", self.edit_resolution, MAX_EDIT_RESOLUTION)):
            if isinstance(value, bool) or not isinstance(value, int) or not 8 <= value <= most:
                raise ValueError(f"{name} must be a whole number in 8 … {most}, got {value!r}")
        if isinstance(self.edits, bool) or not isinstance(self.edits, int) or self.edits < 0:
            raise ValueError(f"edits must be a whole number ≥ 0 (0: no editing table), got {self.edits!r}")


@dataclass
class EvaluationSet:
    """The materials a report evaluates, and where they come from (:func:`evaluation_set`)."""

    data: Path
    """The folder the materials are read from."""
    names: list[str]
    """The evaluated materials, sorted by name."""
    files: dict[str, Path]
    """Every material of ``data``: name → MERL file."""
    out_of_distribution: bool
    """True: the materials of ``data`` that no run saw; False: the runs' test split."""
    trained_on: list[str]
    """The data folders the runs were trained on."""
    excluded: list[str]
    """Out of distribution: the materials of ``data`` left out because a run trained or validated on them."""
    available: int
    """How many materials could be evaluated (``names`` keeps the first ``max_materials`` of them)."""

    def describe(self) -> str:
        """What was evaluated, in words."""
        if not self.out_of_distribution:
            return f"the runs' test split, read from {self.data}"
        which = (f"all {len(self.names)}" if len(self.names) == self.available
                 else f"the first {len(self.names)} (by name) of the {self.available}")
        return f"{which} material{'s' * (self.available != 1)} of {self.data} that no run saw (out-of-distribution)"

    def to_json(self) -> dict:
        """The report's ``evaluation_set``: what was evaluated, from which folder, what was left out."""
        return {"out_of_distribution": self.out_of_distribution, "description": self.describe(),
                "data": str(self.data), "trained_on": self.trained_on, "materials": len(self.names),
                "excluded": self.excluded}


def evaluation_set(runs: list[Run], data: str | os.PathLike | None = None, *, all_materials: bool = False,
                   max_materials: int = 0) -> EvaluationSet:
    """The materials to evaluate runs on.

    Parameters
    ----------
    runs
        The opened runs.
    data
        The materials' folder. For the test split, by default the one the runs were trained on.
    all_materials
        Every material of ``data`` whose name is in no run's training or validation split (out of
        distribution), instead of the runs' common test split.
    max_materials
        Keep at most this many, the first by name (0: all).

    Raises
    ------
    FileNotFoundError
        The folder does not exist, or a test material is not in it.
    ValueError
        The folder holds no MERL file; ``all_materials`` without ``data`` or with nothing left; runs of
        different splits (test split); a negative ``max_materials``.
    """
    if max_materials < 0:
        raise ValueError(f"max_materials must be ≥ 0 (0: all), got {max_materials}")
    trained_on = sorted({str(run.data) for run in runs})
    if all_materials:
        if not data:
            raise ValueError("evaluating every material of a folder (--all) needs that folder: give it with --data DIR")
        folder = Path(data)
        files = {path.stem: path for path in list_materials(folder)}
        seen = {name for run in runs for name in (*run.split.train, *run.split.val)}
        unseen = sorted(set(files) - seen)
        if not unseen:
            raise ValueError(f"all {len(files)} materials of {folder} are in a run's training or validation split: "
                             "none is left to evaluate")
        return EvaluationSet(folder, unseen[: max_materials or None], files, True, trained_on,
                             sorted(seen & set(files)), len(unseen))
    if len({run.split.test for run in runs}) != 1:
        raise ValueError("the runs were trained on different splits; evaluate runs of the same data and seed together")
    folder = Path(data) if data else runs[0].data
    files = {path.stem: path for path in list_materials(folder)}
    test = sorted(runs[0].split.test)
    names = test[: max_materials or None]
    missing = [n for n in names if n not in files]
    if missing:
        raise FileNotFoundError(f"test materials {missing[:3]} not found in {folder}")
    return EvaluationSet(folder, names, files, False, trained_on, [], len(test))


@dataclass
class RunSet:
    """Trained runs of one split and the materials to evaluate them on (see :func:`load_runs`)."""

    runs: list[Path]
    """The run folders, in the order of the method registry (:func:`frenbrdf.presets.method_names`)."""
    models: dict[str, Model]
    """Method → model; the run folder's name is added when a method repeats."""
    data: Path
    """The materials' folder."""
    test: list[str]
    """Names of the evaluated materials, sorted (the test split, or the unseen ones of ``data``)."""
    files: dict[str, Path]
    """Every material of ``data``: name → MERL file."""
    materials: EvaluationSet
    """What is evaluated and why."""


def load_runs(run_dirs, data: str | None = None, max_materials: int = 0, *, all_materials: bool = False,
              materials: EvaluationSet | None = None) -> RunSet:
    """Loads runs (one per method) and finds the materials to evaluate them on.

    Parameters
    ----------
    run_dirs
        Training run folders (each with ``best.pt``, ``config.json`` and ``split.json``).
    data, max_materials, all_materials
        Which materials: see :func:`evaluation_set`.
    materials
        The materials, when chosen already (:func:`evaluate_seeds` gives every seed the same ones).

    Raises
    ------
    FileNotFoundError
        A folder is not a run, or a test material is not in the data folder.
    ValueError
        No runs, runs trained on different splits (test split), no material to evaluate.
    """
    runs = [Run(r) for r in run_dirs]
    if not runs:
        raise ValueError("give at least one run folder")
    order = method_names()  # tables list the methods in the registry's order, whatever order they came in
    runs.sort(key=lambda run: order.index(run.method) if run.method in order else len(order))
    materials = materials or evaluation_set(runs, data, all_materials=all_materials, max_materials=max_materials)
    models = {}
    for run in runs:
        model = run.model()
        label = model.method if model.method not in models else f"{model.method} ({run_label(run.path, run.method)})"
        if label in models:
            raise ValueError(f"two runs of {model.method} would both be called {label!r} ({run.path}); give them "
                             "folders of different names")
        models[label] = model
    return RunSet([run.path for run in runs], models, materials.data, materials.names, materials.files, materials)


def run_label(path: Path, method: str = "") -> str:
    """What tells a run apart from another of its method, the same for every seed: its folder, or for a
    seed's folder (``OUT/seed-S`` of ``frenbrdf train --seeds``) the folder holding it (e.g. ``eta-0.05``),
    or the one above when that is just the method's name (``bank-paper/frenbrdf/seed-S``)."""
    path = Path(path).resolve()
    if not path.name.startswith("seed-"):
        return path.name
    return path.parents[1].name if path.parent.name == method else path.parent.name


def check_out(out_dir, run_dirs, *, data=None, overwrite: bool = False) -> OutputFolder:
    """Where an evaluation may write, checked before any work (:class:`frenbrdf.io.outputs.OutputFolder`): a new or
    empty folder or an earlier evaluation's, not a run folder nor the data folder, nor one holding either; a
    folder holding other entries only with ``overwrite`` (they are kept)."""
    inputs = (*run_dirs, *([data] if data is not None else _trained_on(run_dirs)))
    out = OutputFolder.claim(out_dir, command="evaluate", inputs=inputs, overwrite=overwrite)
    out.check_names(["evaluation.json", "evaluation.md"])
    return out


def _trained_on(run_dirs) -> list[Path]:
    """The data folders the runs name (read without --data): inputs too. A folder that is not a readable run adds
    none here; loading it later says what is wrong with it."""
    folders = []
    for path in run_dirs:
        try:
            folders.append(Run(path).data)
        except (OSError, ValueError):
            continue
    return folders


def pattern_rng(seed: int, pattern: str) -> np.random.Generator:
    """The generator a sampling pattern other than ``merl-bins`` draws an evaluation's samples from: seeded by the
    evaluation's seed and the pattern's name (the same on every machine), whatever other patterns run."""
    return np.random.default_rng([seed, zlib.crc32(pattern.encode())])


def evaluate_runs(run_dirs, out_dir, *, data: str | None = None, config: EvaluateConfig | None = None,
                  materials: EvaluationSet | None = None, overwrite: bool = False) -> dict:
    """Evaluates runs (one per method) on their common test split, or with ``config.all_materials`` on every
    material of ``data`` they never saw; writes tables and figures to ``out_dir`` (:func:`check_out`; or an
    :class:`~frenbrdf.io.outputs.OutputFolder` claimed already) once everything is computed.

    ``materials``: the materials, when chosen already (see :func:`load_runs`). ``config``: default
    :class:`EvaluateConfig`.
    """
    config = EvaluateConfig() if config is None else config
    start = time.perf_counter()
    out = out_dir if isinstance(out_dir, OutputFolder) else check_out(out_dir, run_dirs, data=data,
                                                                       overwrite=overwrite)
    out.check_names([*FIGURE_FILES, "spectrum.png"])  # a user's file under one of these names: refused now, not at the end
    loaded = load_runs(run_dirs, data, config.max_materials, all_materials=config.all_materials, materials=materials)
    runs, models, names, files = loaded.runs, loaded.models, loaded.test, loaded.files
    rng = np.random.default_rng(config.seed)
    scene, edit_scene = Scene(resolution=config.resolution), Scene(resolution=config.edit_resolution)
    # Refinement is seeded by the evaluation's seed: the same config reruns to the same numbers.
    refinement = (None if config.refine == "none"
                  else dataclasses.replace(refine_config(config.refine), seed=config.seed))

    done = _reconstruct_all(models, names, files, config, rng, scene, edit_scene, refinement)
    latents, per_material, renders, spectrum = done.latents, done.per_material, done.renders, done.spectrum
    pairs = edit_pairs(len(names), max(1, config.edits // len(config.weights)) if config.edits else 0, rng)
    edits = edit_rows(models, names, pairs, done.latents, done.edit_truth_linear, config.weights, edit_scene,
                      progress=config.progress)

    first, hardest = rendered_materials(names, per_material)
    report = {"data": str(loaded.data), "runs": [str(r) for r in runs], "test_materials": names,
              "evaluation_set": loaded.materials.to_json(),
              "config": {k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(config).items()},
              "summary": {method: summarise(per_material[method], edits[method]) for method in models},
              "colour": colour_losses(per_material), "rendered": {"first": first, "highest_delta_e": hardest},
              "spectrum": spectrum.summary(),
              "reconstruction": per_material, "editing": edits, "seconds": time.perf_counter() - start}
    if refinement:
        report["refinement"] = {"budget": config.refine, "config": dataclasses.asdict(refinement),
                                "seconds_per_material": {method: float(np.mean([r["refine_seconds"] for r in rows]))
                                                         for method, rows in per_material.items()}}
    edit_pair = (names[pairs[0][0]], names[pairs[0][1]]) if pairs else None
    with out.staged() as staging:
        save_json(staging / "evaluation.json", report)
        write_text(staging / "evaluation.md", report_markdown(report))
        write_figures(staging, first + hardest, renders, per_material, models, latents[""], edit_pair,
                      done.edit_truth_linear, config.weights, config.edit_resolution)
        spectrum.write(staging / "spectrum.png", f"Per-degree power spectra of the {len(names)} evaluated materials "
                       "(mean) and each method's encoder-only reconstructions; dashed: their error (L_fre variant "
                       "'tone')")
    return report


@dataclass
class _Reconstructed:
    """What the reconstruction pass of :func:`evaluate_runs` keeps for the editing, the tables and the figures."""

    latents: dict[str, dict[str, dict[str, np.ndarray]]]
    """By prefix of the metrics they give (the encoder's ``""``, the refined ``"refined_"``), method, material."""
    per_material: dict[str, list[dict]]
    """Each method's metric rows, one per material."""
    renders: dict[str, dict[str, np.ndarray]]
    """By material: the truth's display image and each method's; only for the materials ``renders.png`` can show."""
    edit_truth_linear: dict[str, np.ndarray]
    """The truth's linear render at the editing resolution, by material."""
    spectrum: SpectrumSummary
    """Each method's decoded latents against the true tables."""


def _reconstruct_all(models: dict, names: list[str], files: dict, config: EvaluateConfig, rng: np.random.Generator,
                     scene: Scene, edit_scene: Scene, refinement) -> _Reconstructed:
    """Encodes (and refines) every material from each pattern's samples with every model, and scores it."""
    mask = material_mask(scene)
    done = _Reconstructed({"": {m: {} for m in models}}, {m: [] for m in models}, {}, {}, SpectrumSummary())
    if refinement:
        done.latents["refined_"] = {m: {} for m in models}
    scoring = Scoring(scene, mask, FrequencyMetric(), refinement)
    rngs = {pattern: rng if pattern == DEFAULT_PATTERN else pattern_rng(config.seed, pattern)
            for pattern in config.patterns}
    mean_delta_e: dict[str, float] = {}
    for name in tqdm(names, desc="reconstruction", disable=not config.progress):
        truth = read_measured(files[name])  # a .bsdf renders as measured, not through its table
        table = as_table(truth)
        samples = {pattern: pattern_samples(truth, pattern, config.samples, rngs[pattern], table=table)
                   for pattern in config.patterns}
        done.edit_truth_linear[name] = render_linear(truth, edit_scene)
        truth_linear = render_linear(truth, scene)
        truth_image, highlight = tonemap(truth_linear), highlight_mask(truth_linear, mask)
        done.renders[name] = {"truth": truth_image}
        decoded = {}
        for method, model in models.items():
            scored = {pattern: scoring.reconstruct(model, drawn, table, truth_image, highlight)
                      for pattern, drawn in samples.items()}
            primary = scored[config.patterns[0]]  # the first pattern's: the figures show it
            done.latents[""][method][name] = primary.z
            done.renders[name][method] = primary.image
            decoded[method] = model.decode(primary.z)
            if primary.refined is not None and primary.refined_image is not None:
                done.latents["refined_"][method][name] = primary.refined.z
                done.renders[name][f"{method} refined"] = primary.refined_image
            done.per_material[method].append({"material": name, **{
                key + pattern_suffix(pattern, config.patterns): value
                for pattern, one in scored.items() for key, value in one.metrics.items()}})
        done.spectrum.add(table, decoded)
        mean_delta_e[name] = float(np.mean([rows[-1]["delta_e"] for rows in done.per_material.values()]))
        drop_unshown_renders(done.renders, names, mean_delta_e)
    return done


def evaluate_seeds(run_dirs, out_dir, *, data: str | None = None,
                   config: EvaluateConfig | None = None, overwrite: bool = False) -> dict:
    """Evaluates runs of one or several seeds: one run per method and seed (:mod:`frenbrdf.evaluation.statistics`).

    Runs are grouped by their split (a seed's split); with one group this is
    :func:`evaluate_runs`. With several, each seed is evaluated into ``OUT/seed-S/`` and
    ``OUT/evaluation.{md,json}`` compare the methods over the seeds: mean ± sd and paired
    95 % t-intervals against FreNBRDF; the JSON keeps every per-material, per-seed number.
    With ``config.all_materials`` every seed is evaluated on the same materials: those of
    ``data`` that no run of any seed trained or validated on. Everything that can be checked (the
    output folder, every run, the methods of every seed) is checked before anything is computed.
    ``config``: default :class:`EvaluateConfig`.
    """
    config = EvaluateConfig() if config is None else config
    out = check_out(out_dir, run_dirs, data=data, overwrite=overwrite)
    runs = [Run(path) for path in run_dirs]
    groups: dict[int, list] = {}
    splits: dict[int, tuple] = {}
    for run in runs:
        split = run.split
        if split.seed in splits and splits[split.seed] != split.test:
            raise ValueError(f"runs of seed {split.seed} were trained on different splits")
        splits[split.seed] = split.test
        groups.setdefault(split.seed, []).append(run.path)
    for run in runs:  # a folder that is not a complete run fails now, not after the first seed's evaluation
        run.config, run.split  # noqa: B018 (read and checked)
        if not (run.path / "best.pt").is_file():
            raise FileNotFoundError(f"{run.path} holds no best.pt: training has not finished an epoch")
    methods = {seed: sorted(Run(path).method for path in group) for seed, group in groups.items()}
    if len(groups) > 1:
        if len({tuple(m) for m in methods.values()}) != 1:
            raise ValueError("every seed needs runs of the same methods; got "
                             + "; ".join(f"seed {seed}: {', '.join(m)}" for seed, m in sorted(methods.items())))
        if REFERENCE not in next(iter(methods.values())):
            raise ValueError(f"comparing seeds needs a run of {REFERENCE!r}, the reference of the paired intervals")
    materials = (evaluation_set(runs, data, all_materials=True, max_materials=config.max_materials)
                 if config.all_materials else None)
    if len(groups) == 1:
        return evaluate_runs(next(iter(groups.values())), out, data=data, config=config, materials=materials)
    out.check_names(f"seed-{seed}" for seed in groups)
    with out.staged() as staging:
        return _compare_seeds(runs, groups, staging, data, config, materials)


def _compare_seeds(runs: list, groups: dict, staging: Path, data, config: EvaluateConfig, materials) -> dict:
    """:func:`evaluate_seeds` with several seeds: each evaluated into ``staging/seed-S``, then compared."""
    reports = {seed: evaluate_runs(group, staging / f"seed-{seed}", data=data, config=config, materials=materials)
               for seed, group in sorted(groups.items())}
    # A row without a value on every seed (editing of a single material: None) cannot be compared.
    keys = [key for key, _ in table_rows(config.refine, config.patterns)
            if all(v.get(key) is not None and np.isfinite(v[key]) for r in reports.values()
                   for v in r["summary"].values())]
    comparison = compare_seeds({seed: r["summary"] for seed, r in reports.items()}, keys)
    methods = reports[min(reports)]["reconstruction"]
    all_rows = {m: [row for r in reports.values() for row in r["reconstruction"][m]] for m in methods}
    evaluated = {**reports[min(reports)]["evaluation_set"], "trained_on": sorted({str(run.data) for run in runs})}
    report = {"comparison": comparison, "evaluation_set": evaluated, "colour": colour_losses(all_rows),
              "seeds": {str(seed): r for seed, r in reports.items()},
              "test_materials": sum(len(r["test_materials"]) for r in reports.values()),
              "seconds": sum(r["seconds"] for r in reports.values())}
    save_json(staging / "evaluation.json", report)
    write_text(staging / "evaluation.md", seeds_markdown(report))
    return report
