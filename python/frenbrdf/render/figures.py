"""The figures of an evaluation (:func:`frenbrdf.evaluation.evaluate.evaluate_runs`): histograms, renders, an edit.

- ``histograms.png``: per method, the per-material RMSE, PSNR, SSIM and ΔE, with the mean
  (solid) and ± one standard deviation (dashed).
- ``renders.png``: truth | each method (and its refined render beside it, when the evaluation refined),
  for the materials :func:`rendered_materials` picks.
- ``interpolation.png``: the first edited pair at t = 0, the interior weights and 1.

And :func:`titled_row`, the renders side by side under their titles that ``reconstruct`` and ``edit`` write.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .renderer import Scene, render_linear, save_figure, tonemap

#: The titles' largest and smallest font size (points at 100 dpi); a row too narrow for the smallest goes untitled.
TITLE_POINTS = (9.0, 5.0)


def titled_row(images: list[np.ndarray], titles: Sequence[str | None]) -> np.ndarray:
    """Images of one height side by side, each under its title (None: untitled, e.g. a gap), as one display image.

    The pixels are the images' own; only the band of titles above them is drawn by matplotlib, so the row costs
    little more memory than the images. The titles share one size, the largest at which each fits its column.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    row = np.concatenate(images, axis=1)
    widths = [image.shape[1] for image in images]
    # Text is about 0.55 em a character wide; an em is points × 100/72 pixels at 100 dpi.
    size = min([TITLE_POINTS[0], *(0.95 * width / (0.55 * len(title) * 100 / 72)
                                   for title, width in zip(titles, widths, strict=True) if title)])
    if size < TITLE_POINTS[1] or not any(titles):
        return row
    band = int(np.ceil(2.2 * size * 100 / 72))
    figure = Figure(figsize=(row.shape[1] / 100, band / 100), dpi=100, facecolor="black")
    left = np.cumsum([0, *widths]) / row.shape[1]
    for title, start, stop in zip(titles, left[:-1], left[1:], strict=True):
        if title:
            figure.text((start + stop) / 2, 0.45, title, color="white", fontsize=size, ha="center", va="center")
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    drawn = np.asarray(canvas.buffer_rgba())[:band, :row.shape[1], :3].astype(row.dtype) / 255
    return np.concatenate([drawn, row], axis=0)


#: Per-material metrics shown in ``histograms.png``, one column each.
HISTOGRAM_METRICS = (("rmse", "RMSE"), ("psnr", "PSNR"), ("ssim", "SSIM"), ("delta_e", "ΔE"))


#: What :func:`write_figures` writes (``interpolation.png`` only where there was a pair to edit).
FIGURE_FILES = ("histograms.png", "renders.png", "interpolation.png")
#: ``renders.png`` shows the first this many materials and this many of the rest, those highest in ΔE.
FIRST_SHOWN, WORST_SHOWN = 4, 4


def rendered_materials(names: list[str], per_material: dict[str, list[dict]], first: int = FIRST_SHOWN,
                       worst: int = WORST_SHOWN) -> tuple[list[str], list[str]]:
    """The materials of ``renders.png``: the first ``first`` names, and the ``worst`` others with the
    highest ΔE averaged over the methods (highest first), so the hard cases are always in the picture."""
    mean_delta_e = {name: np.mean([row["delta_e"] for rows in per_material.values() for row in rows
                                   if row["material"] == name]) for name in names[first:]}
    return names[:first], sorted(mean_delta_e, key=lambda name: -mean_delta_e[name])[:worst]


def drop_unshown_renders(renders: dict, names: list[str], mean_delta_e: dict[str, float]) -> None:
    """Drops, as an evaluation goes, the display images of materials that :func:`rendered_materials` can no longer
    choose (the first ones and those highest in mean ΔE so far stay): it holds eight materials' renders, not all."""
    first = names[:FIRST_SHOWN]
    worst = sorted((n for n in mean_delta_e if n not in first), key=lambda n: -mean_delta_e[n])[:WORST_SHOWN]
    for name in set(renders) - set(first) - set(worst):
        del renders[name]

def write_figures(out: Path, shown: list[str], renders: dict, per_material: dict, models: dict, latents: dict,
                  edit_pair: tuple[str, str] | None, edit_truth_linear: dict, weights, edit_resolution: int) -> None:
    """Writes the three figures into ``out``.

    Parameters
    ----------
    out
        The folder the figures are written to.
    shown
        Materials of ``renders.png``, in order (:func:`rendered_materials`).
    renders
        Material → ``{"truth": image, method: image, …}`` (display images), in the order of the columns of
        ``renders.png`` (e.g. ``"<method> refined"`` after each method).
    per_material
        Method → reconstruction rows (each with the :data:`HISTOGRAM_METRICS`).
    models, latents
        Method → model, and method → material → latent (to decode the interpolation strip).
    edit_pair
        The two materials of ``interpolation.png`` (None: no figure, there was no pair).
    edit_truth_linear
        Material → linear render at ``edit_resolution``.
    weights
        The interior interpolation weights.
    edit_resolution
        Pixels per side of the interpolation strip's renders.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = list(models)
    figure, axes = plt.subplots(len(methods), len(HISTOGRAM_METRICS), figsize=(4 * len(HISTOGRAM_METRICS),
                                                                                3 * len(methods)), squeeze=False)
    for row, method in enumerate(methods):
        for col, (metric, label) in enumerate(HISTOGRAM_METRICS):
            values = np.array([r[metric] for r in per_material[method]])
            values = values[np.isfinite(values)]
            axis = axes[row, col]
            axis.hist(values, bins=20, color="#4c72b0", alpha=0.8)
            if len(values):
                mean, std = values.mean(), values.std()
                axis.axvline(mean, color="k", linestyle="-")
                for edge in (mean - std, mean + std):
                    axis.axvline(edge, color="k", linestyle="--")
            axis.set_title(f"{method}: {label}")
    figure.tight_layout()
    save_figure(figure, out / "histograms.png")
    plt.close(figure)

    columns = list(renders[shown[0]])  # truth, then each method (and its refined render)
    figure, axes = plt.subplots(len(shown), len(columns), figsize=(2 * len(columns), 2 * len(shown)), squeeze=False)
    for row, name in enumerate(shown):
        for col, key in enumerate(columns):
            axes[row, col].imshow(renders[name][key])
            axes[row, col].set_xticks([])
            axes[row, col].set_yticks([])
            if row == 0:
                axes[row, col].set_title(key, fontsize=9)
        axes[row, 0].set_ylabel(name, fontsize=7)
    figure.tight_layout()
    save_figure(figure, out / "renders.png")
    plt.close(figure)

    if edit_pair is None:
        return
    a, b = edit_pair
    scene = Scene(resolution=edit_resolution)
    strip = (0.0, *weights, 1.0)  # the end points too, for a person to see where edits go
    figure, axes = plt.subplots(1 + len(methods), len(strip), figsize=(1.6 * len(strip), 1.7 * (1 + len(methods))),
                                squeeze=False)
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
