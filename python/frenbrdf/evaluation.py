"""Evaluation (docs/method.md §7): reconstruction and editing tables, histograms, render grids.

- Reconstruction: each test material is encoded from N random valid bins (default 4000,
  the same bins for every method), decoded, rendered and compared with the render of the
  true table: RMSE, PSNR, SSIM (scikit-image, data_range 1) over the lit material pixels
  (:func:`frenbrdf.render.material_mask`), and the frequency loss.
- Editing: each unordered pair (a, b) of test materials at most once and interior
  t ∈ {0.25, 0.5, 0.75}; the truth is
  the table (1 − t)·a + t·b (its render is the same blend of the linear renders, since
  rendering is linear in the BRDF), the prediction decode((1 − t)·z_a + t·z_b).

``evaluate_runs`` does both for several runs side by side and writes Markdown, JSON and
PNG figures; ``frenbrdf evaluate`` is its command line.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from .atomic import save_json, write_text
from .data import list_materials
from .losses import FrequencyLoss, FrequencyLossConfig, FrequencyTruth, spectral_distance
from .merl import N_BINS, SHAPE, merl_bin_angles, read_merl
from .models.autoencoder import Model
from .presets import method_names
from .render import Scene, material_mask, render_linear, save_figure, tonemap
from .statistics import compare_seeds, markdown
from .training.run import Run

#: The paper's numbers (MERL, their protocol), docs/method.md §7.
#: Its L_fre (×10³: hyperbrdf 6.74, nbrdf 6.80, frenbrdf 0.23) is a mean over coefficients on its own
#: data and settings, not comparable with ours (normalised on the sphere), so it is not listed.
PAPER = {
    "hyperbrdf": {"rmse_x100": 6.89, "psnr": 26.3, "ssim_x10": 9.26, "edit_psnr": 22.4, "edit_ssim_x10": 9.13},
    "nbrdf": {"rmse_x100": 6.60, "psnr": 29.2, "ssim_x10": 9.50, "edit_psnr": 27.6, "edit_ssim_x10": 9.42},
    "frenbrdf": {"rmse_x100": 6.74, "psnr": 29.9, "ssim_x10": 9.88, "edit_psnr": 30.1, "edit_ssim_x10": 9.82},
}
ROWS = [("rmse_x100", "Recon RMSE×10² ↓"), ("psnr", "Recon PSNR ↑"), ("ssim_x10", "Recon SSIM×10 ↑"),
        ("lfre", "Recon L_fre ↓"), ("edit_psnr", "Edit PSNR ↑"), ("edit_ssim_x10", "Edit SSIM×10 ↑")]


def image_metrics(truth: np.ndarray, prediction: np.ndarray, mask: np.ndarray | None = None) -> dict[str, float]:
    """RMSE, PSNR, SSIM and colour difference ΔE of two display images in [0, 1] ``(H, W, 3)`` over
    the pixels of ``mask`` ``(H, W)`` (default: all; evaluation passes :func:`frenbrdf.render.material_mask`).

    RMSE and PSNR (data range 1) are those of the masked pixels; SSIM is scikit-image's SSIM
    map averaged over them (its 7×7 windows near the silhouette still see some background);
    ``delta_e`` is :func:`delta_e`.
    """
    from skimage.metrics import structural_similarity

    mask = np.ones(truth.shape[:2], dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if mask.shape != truth.shape[:2] or truth.shape != prediction.shape or not mask.any():
        raise ValueError(f"images {truth.shape} and {prediction.shape} need a non-empty mask of shape "
                         f"{truth.shape[:2]}, got {mask.shape}")
    mse = float(np.mean((truth[mask] - prediction[mask]) ** 2))
    psnr = 10 * np.log10(1.0 / mse) if mse > 0 else float("inf")
    _, ssim_map = structural_similarity(truth, prediction, data_range=1.0, channel_axis=-1, full=True)
    return {"rmse": float(np.sqrt(mse)), "psnr": float(psnr), "ssim": float(ssim_map[mask].mean()),
            "delta_e": delta_e(truth, prediction, mask)}


def delta_e(truth: np.ndarray, prediction: np.ndarray, mask: np.ndarray) -> float:
    """Mean CIEDE2000 colour difference of two display images in [0, 1] ``(H, W, 3)`` over ``mask``.

    The images are read as sRGB (scikit-image's ``rgb2lab``, D65); ours are gamma 2.2, which
    sRGB's curve follows to within a few per cent. ΔE ≈ 1 is the smallest difference a person
    sees side by side; above ~5 the colours read as different.
    """
    from skimage.color import deltaE_ciede2000, rgb2lab

    return float(deltaE_ciede2000(rgb2lab(truth[mask]), rgb2lab(prediction[mask])).mean())


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
    """Evaluate at most this many test materials (0: all)."""
    progress: bool = True


def _bin_directions(bins: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ω_i, ω_o) of flat bin indices (φ_h = 0), each ``(len(bins), 3)``.

    The angles of :func:`frenbrdf.merl_bin_rusinkiewicz` at those bins only (the same
    values, without building the whole grid).
    """
    from .coords import rusinkiewicz_to_directions

    theta_h, theta_d, phi_d = merl_bin_angles()
    i, j, k = np.unravel_index(np.asarray(bins), SHAPE[1:])
    return rusinkiewicz_to_directions(np.stack([theta_h[i], np.zeros(i.shape), theta_d[j], phi_d[k]], axis=-1))


class FrequencyMetric:
    """L_fre between a true table and a decoded latent, in the model's mapped space.

    The settings are fixed (default: :class:`FrequencyLossConfig`'s), whatever the model was
    trained with, so that values of different models compare.
    """

    def __init__(self, config: FrequencyLossConfig = FrequencyLossConfig()):
        self.truth, self.loss = FrequencyTruth(config), FrequencyLoss(config)

    def __call__(self, model: Model, table: np.ndarray, z: np.ndarray) -> float:
        flat = table.reshape(3, N_BINS)
        valid = np.all(flat >= 0, axis=0)
        with np.errstate(invalid="ignore"):
            mapped = model.mapping.forward(np.where(valid, flat, 0.0), model.mapping.reference_bins())
        true = self.truth.coefficients(np.nan_to_num(mapped).T, valid)
        with torch.no_grad():
            params = model.network.decoder(torch.from_numpy(z[None].astype(np.float32)))
            predicted = self.loss.predicted_coefficients(params)[0].numpy()
        return float(spectral_distance(predicted, true))


def edit_pairs(n_materials: int, most: int, rng: np.random.Generator) -> list[tuple[int, int]]:
    """Unordered pairs of distinct materials, each at most once: all of them, or ``most`` drawn at random."""
    pairs = list(itertools.combinations(range(n_materials), 2))
    if len(pairs) > most:
        pairs = [pairs[i] for i in sorted(rng.choice(len(pairs), size=most, replace=False))]
    return pairs


def sample_bins(table: np.ndarray, rng: np.random.Generator, samples: int) -> np.ndarray:
    """``samples`` random valid bins (flat indices) of a MERL table, with replacement only if too few."""
    valid_bins = np.flatnonzero(np.all(table.reshape(3, N_BINS) >= 0, axis=0))
    return rng.choice(valid_bins, size=samples, replace=len(valid_bins) < samples)


def reconstruct(model: Model, table: np.ndarray, bins: np.ndarray, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Encodes a table from the samples at ``bins``, decodes and renders it: (z, display image)."""
    wi, wo = _bin_directions(bins)
    z = model.encode(table.reshape(3, N_BINS)[:, bins].T, (wi, wo))
    return z, tonemap(render_linear(model.decode(z)[0], scene))


def reconstruction_rows(model: Model, files, *, samples: int = 4000, resolution: int = 256, seed: int = 0,
                        frequency_metric: FrequencyMetric | None | bool = None, progress: bool = True) -> list[dict]:
    """Reconstruction metrics of one model on MERL files (e.g. a validation split), one row each.

    Each material is encoded from ``samples`` random valid bins (drawn from ``seed``, in the
    order of ``files``, as :func:`evaluate_runs` draws them), decoded, rendered and compared
    with the render of the true table: RMSE, PSNR, SSIM and L_fre (``frequency_metric``:
    None for the default one, an instance to reuse across calls, False for no L_fre).
    """
    rng = np.random.default_rng(seed)
    scene = Scene(resolution=resolution)
    if frequency_metric is None:
        frequency_metric = FrequencyMetric()
    rows = []
    for path in tqdm(list(files), desc="reconstruction", disable=not progress, leave=False):
        path = Path(path)
        table = read_merl(path)
        bins = sample_bins(table, rng, samples)
        z, image = reconstruct(model, table, bins, scene)
        metrics = image_metrics(tonemap(render_linear(table, scene)), image, material_mask(scene))
        if frequency_metric is not False:
            metrics["lfre"] = frequency_metric(model, table, z)
        rows.append({"material": path.stem, **metrics})
    return rows


@dataclass
class RunSet:
    """Trained runs of one split and their test materials (see :func:`load_runs`)."""

    runs: list[Path]
    """The run folders, in the order of the method registry (:func:`frenbrdf.presets.method_names`)."""
    models: dict[str, Model]
    """Method → model; the run folder's name is added when a method repeats."""
    data: Path
    """The materials' folder."""
    test: list[str]
    """Names of the test materials, sorted (at most ``max_materials``)."""
    files: dict[str, Path]
    """Every material of ``data``: name → MERL file."""


def load_runs(run_dirs, data: str | None = None, max_materials: int = 0) -> RunSet:
    """Loads runs (one per method) trained on the same split and finds their test materials.

    Parameters
    ----------
    run_dirs
        Training run folders (each with ``best.pt``, ``config.json`` and ``split.json``).
    data
        The materials' folder; by default the one recorded in the runs' ``config.json``.
    max_materials
        Keep at most this many test materials (0: all).

    Raises
    ------
    FileNotFoundError
        A folder is not a run, or a test material is not in the data folder.
    ValueError
        No runs, or runs trained on different splits.
    """
    runs = [Run(r) for r in run_dirs]
    if not runs:
        raise ValueError("give at least one run folder")
    order = method_names()  # tables list the methods in the registry's order, whatever order they came in
    runs.sort(key=lambda run: order.index(run.method) if run.method in order else len(order))
    models, test_sets, data_dirs = {}, [], set()
    for run in runs:
        model = run.model()
        name = model.method if model.method not in models else f"{model.method} ({run.path.name})"
        models[name] = model
        test_sets.append(run.split.test)
        data_dirs.add(run.data)
    if len(set(test_sets)) != 1:
        raise ValueError("the runs were trained on different splits; evaluate runs of the same data and seed together")
    data_dir = Path(data) if data else Path(data_dirs.pop())
    files = {path.stem: path for path in list_materials(data_dir)}
    names = sorted(test_sets[0])[: max_materials or None]
    missing = [n for n in names if n not in files]
    if missing:
        raise FileNotFoundError(f"test materials {missing[:3]} not found in {data_dir}")
    return RunSet([run.path for run in runs], models, data_dir, names, files)


def evaluate_runs(run_dirs, out_dir, *, data: str | None = None, config: EvaluateConfig = EvaluateConfig()) -> dict:
    """Evaluates runs (one per method) on their common test split; writes tables and figures to ``out_dir``."""
    start = time.perf_counter()
    loaded = load_runs(run_dirs, data, config.max_materials)
    runs, models, data_dir, names, files = loaded.runs, loaded.models, loaded.data, loaded.test, loaded.files
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(config.seed)
    scene, edit_scene = Scene(resolution=config.resolution), Scene(resolution=config.edit_resolution)
    mask, edit_mask = material_mask(scene), material_mask(edit_scene)
    frequency_metric = FrequencyMetric()
    show = config.progress

    # Reconstruction.
    truth_linear, edit_truth_linear, latents = {}, {}, {m: {} for m in models}
    per_material = {m: [] for m in models}
    renders = {}
    for name in tqdm(names, desc="reconstruction", disable=not show):
        table = read_merl(files[name])
        bins = sample_bins(table, rng, config.samples)
        truth_linear[name] = render_linear(table, scene)
        edit_truth_linear[name] = render_linear(table, edit_scene)
        truth_image = tonemap(truth_linear[name])
        renders[name] = {"truth": truth_image}
        for method, model in models.items():
            z, image = reconstruct(model, table, bins, scene)
            latents[method][name] = z
            renders[name][method] = image
            metrics = image_metrics(truth_image, image, mask)
            metrics["lfre"] = frequency_metric(model, table, z)
            per_material[method].append({"material": name, **metrics})

    # Editing.
    pairs = edit_pairs(len(names), max(1, config.edits // len(config.weights)), rng)
    edits = {m: [] for m in models}
    with tqdm(total=len(pairs) * len(config.weights) * len(models), desc="editing", disable=not show) as bar:
        for a, b in pairs:
            name_a, name_b = names[a], names[b]
            for t in config.weights:
                truth_image = tonemap((1 - t) * edit_truth_linear[name_a] + t * edit_truth_linear[name_b])
                for method, model in models.items():
                    z = (1 - t) * latents[method][name_a] + t * latents[method][name_b]
                    image = tonemap(render_linear(model.decode(z)[0], edit_scene))
                    edits[method].append({"a": name_a, "b": name_b, "t": t, **image_metrics(truth_image, image, edit_mask)})
                    bar.update()

    summary = {}
    for method in models:
        rows = per_material[method]
        summary[method] = {
            "rmse_x100": 100 * np.mean([r["rmse"] for r in rows]),
            "psnr": np.mean([r["psnr"] for r in rows]),
            "ssim_x10": 10 * np.mean([r["ssim"] for r in rows]),
            "lfre": np.mean([r["lfre"] for r in rows]),
            "edit_psnr": np.mean([r["psnr"] for r in edits[method]]) if edits[method] else float("nan"),
            "edit_ssim_x10": 10 * np.mean([r["ssim"] for r in edits[method]]) if edits[method] else float("nan"),
        }
        summary[method] = {k: float(v) for k, v in summary[method].items()}
    report = {"data": str(data_dir), "runs": [str(r) for r in runs], "test_materials": names,
              "config": {k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(config).items()},
              "summary": summary, "reconstruction": per_material, "editing": edits,
              "seconds": time.perf_counter() - start}
    save_json(out / "evaluation.json", report)
    write_text(out / "evaluation.md", report_markdown(report))
    _figures(out, names, renders, per_material, models, latents, pairs, edit_truth_linear, config)
    return report


def evaluate_seeds(run_dirs, out_dir, *, data: str | None = None,
                   config: EvaluateConfig = EvaluateConfig()) -> dict:
    """Evaluates runs of one or several seeds: one run per method and seed (:mod:`frenbrdf.statistics`).

    Runs are grouped by their split (a seed's split); with one group this is
    :func:`evaluate_runs`. With several, each seed is evaluated into ``OUT/seed-S/`` and
    ``OUT/evaluation.{md,json}`` compare the methods over the seeds: mean ± sd and paired
    95 % t-intervals against FreNBRDF; the JSON keeps every per-material, per-seed number.
    """
    groups: dict[int, list] = {}
    splits: dict[int, tuple] = {}
    for run in map(Run, run_dirs):
        split = run.split
        if split.seed in splits and splits[split.seed] != split.test:
            raise ValueError(f"runs of seed {split.seed} were trained on different splits")
        splits[split.seed] = split.test
        groups.setdefault(split.seed, []).append(run.path)
    if len(groups) == 1:
        return evaluate_runs(next(iter(groups.values())), out_dir, data=data, config=config)
    out = Path(out_dir)
    reports = {seed: evaluate_runs(runs, out / f"seed-{seed}", data=data, config=config)
               for seed, runs in sorted(groups.items())}
    comparison = compare_seeds({seed: r["summary"] for seed, r in reports.items()}, [key for key, _ in ROWS])
    report = {"comparison": comparison, "seeds": {str(seed): r for seed, r in reports.items()},
              "test_materials": sum(len(r["test_materials"]) for r in reports.values()),
              "seconds": sum(r["seconds"] for r in reports.values())}
    save_json(out / "evaluation.json", report)
    write_text(out / "evaluation.md", seeds_markdown(report))
    return report


def seeds_markdown(report: dict) -> str:
    """The over-seeds table of :func:`evaluate_seeds`, with what was measured."""
    first = next(iter(report["seeds"].values()))
    n_edits = sum(len(e) for e in first["editing"].values()) // max(1, len(first["summary"]))
    return (f"Reconstruction on each seed's test materials ({report['test_materials']} in all); editing over "
            f"{n_edits} interpolations per seed (each unordered pair of test materials at most once, "
            "t ∈ {0.25, 0.5, 0.75}). RMSE, PSNR and SSIM over the lit material pixels (background excluded); "
            "L_fre normalised on the sphere (docs/method.md §5). Per seed: `seed-S/evaluation.md`.\n\n"
            + markdown(report["comparison"], dict(ROWS)))


def report_markdown(report: dict) -> str:
    """The Markdown table of a report of :func:`evaluate_runs`."""
    n_edits = sum(len(e) for e in report["editing"].values()) // max(1, len(report["summary"]))
    return markdown_table(report["summary"], len(report["test_materials"]), n_edits)


def markdown_table(summary: dict, n_materials: int, n_edits: int) -> str:
    """The reconstruction and editing table, methods side by side, with the paper's numbers."""
    methods = list(summary)
    header = "| | " + " | ".join(methods) + " | " + " | ".join(f"paper: {m}" for m in PAPER) + " |"
    lines = [f"Reconstruction on {n_materials} test materials; editing over {n_edits} interpolations (each "
             "unordered pair of test materials at most once, t ∈ {0.25, 0.5, 0.75}). RMSE, PSNR and SSIM over "
             "the lit material pixels of the renders (background excluded); L_fre normalised on the sphere "
             "(docs/method.md §5).", "",
             header, "|---" * (1 + len(methods) + len(PAPER)) + "|"]
    for key, label in ROWS:
        ours = " | ".join(f"{summary[m][key]:.3g}" for m in methods)
        paper = " | ".join(f"{PAPER[m].get(key, '–')}" for m in PAPER)
        lines.append(f"| {label} | {ours} | {paper} |")
    return "\n".join(lines) + "\n"


def _figures(out: Path, names, renders, per_material, models, latents, pairs, edit_truth_linear, config) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = list(models)
    # Histograms per method and metric, with the mean (solid) and ± one standard deviation (dashed).
    figure, axes = plt.subplots(len(methods), 3, figsize=(12, 3 * len(methods)), squeeze=False)
    for row, method in enumerate(methods):
        for col, metric in enumerate(("rmse", "psnr", "ssim")):
            values = np.array([r[metric] for r in per_material[method]])
            values = values[np.isfinite(values)]
            axis = axes[row, col]
            axis.hist(values, bins=20, color="#4c72b0", alpha=0.8)
            if len(values):
                mean, std = values.mean(), values.std()
                axis.axvline(mean, color="k", linestyle="-")
                for edge in (mean - std, mean + std):
                    axis.axvline(edge, color="k", linestyle="--")
            axis.set_title(f"{method}: {metric.upper()}")
    figure.tight_layout()
    save_figure(figure, out / "histograms.png")
    plt.close(figure)

    # A grid of renders: truth | each method, for up to 8 materials.
    shown = names[:8]
    figure, axes = plt.subplots(len(shown), 1 + len(methods), figsize=(2 * (1 + len(methods)), 2 * len(shown)),
                                squeeze=False)
    for row, name in enumerate(shown):
        for col, key in enumerate(["truth", *methods]):
            axes[row, col].imshow(renders[name][key])
            axes[row, col].set_xticks([])
            axes[row, col].set_yticks([])
            if row == 0:
                axes[row, col].set_title(key, fontsize=9)
        axes[row, 0].set_ylabel(name, fontsize=7)
    figure.tight_layout()
    save_figure(figure, out / "renders.png")
    plt.close(figure)

    # Interpolation strips for the first pair: truth row, then each method.
    if pairs:
        a, b = names[pairs[0][0]], names[pairs[0][1]]
        scene = Scene(resolution=config.edit_resolution)
        strip = (0.0, *config.weights, 1.0)  # the end points too, for a person to see where edits go
        figure, axes = plt.subplots(1 + len(methods), len(strip),
                                    figsize=(1.6 * len(strip), 1.7 * (1 + len(methods))), squeeze=False)
        for col, t in enumerate(strip):
            axes[0, col].imshow(tonemap((1 - t) * edit_truth_linear[a] + t * edit_truth_linear[b]))
            axes[0, col].set_title(f"t = {t:g}", fontsize=9)
            for row, method in enumerate(methods, start=1):
                z = (1 - t) * latents[method][a] + t * latents[method][b]
                axes[row, col].imshow(tonemap(render_linear(models[method].decode(z)[0], scene)))
        for row, label in enumerate(["truth", *methods]):
            axes[row, 0].set_ylabel(label, fontsize=9)
        for axis in axes.flat:
            axis.set_xticks([])
            axis.set_yticks([])
        figure.suptitle(f"{a} → {b}", fontsize=9)
        figure.tight_layout()
        save_figure(figure, out / "interpolation.png")
        plt.close(figure)
