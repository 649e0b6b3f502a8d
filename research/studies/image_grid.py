"""A grid of renders for the studies' pictures: one row per case, each image titled, each row labelled."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np


def save_image_grid(rows: list[tuple[str, list[tuple[str, np.ndarray]]]], path: str | Path) -> None:
    """``rows``: (row label, [(title, display image), ...]) each, the same number of images in every row; written to
    ``path`` (its suffix chooses the format)."""
    columns = len(rows[0][1])
    figure, axes = plt.subplots(len(rows), columns, figsize=(2 * columns, 2.1 * len(rows)), squeeze=False)
    for row_axes, (label, images) in zip(axes, rows, strict=True):
        for axis, (title, image) in zip(row_axes, images, strict=True):
            axis.imshow(np.clip(image, 0, 1))
            axis.set_title(title, fontsize=7)
            axis.set_xticks([]), axis.set_yticks([])
        row_axes[0].set_ylabel(label, fontsize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=80)
    plt.close(figure)


def reconstruction_row(truth: Any, drawn: Any, columns: list[tuple[str, Any, Any]], scene: Any,
                       mask: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """The truth's render, then each column's reconstruction from the samples ``drawn``: ``columns`` are (title,
    model, RefineConfig); each title may hold ``{seconds}`` (the reconstruction's) and gets its PSNR / ΔE below."""
    from frenbrdf.render.renderer import render_linear, tonemap
    from frenbrdf.render.scoring import image_metrics, refined_reconstruction

    truth_image = tonemap(render_linear(truth, scene))
    images = [("truth", truth_image)]
    for title, model, config in columns:
        _, image, seconds = refined_reconstruction(model, drawn, scene, config)
        metrics = image_metrics(truth_image, image, mask)
        images.append((f"{title.format(seconds=seconds)}\n{metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.1f}",
                       image))
    return images


def material_row(path: Path, columns: list[tuple[str, Any, Any]], scene: Any, mask: np.ndarray,
                 pattern: str = "merl-bins", count: int = 4000, draw: int = 0) -> list[tuple[str, np.ndarray]]:
    """:func:`reconstruction_row` of the material at ``path`` (a table or a ``.bsdf`` measurement) from ``count``
    samples of ``pattern``, draw ``draw``, as compare_models.py draws and refines them (the refinement seeded by
    the draw: ``full``'s result on one material moves by several dB from one seed to another)."""
    from compare_models import condition_rng

    from frenbrdf.io import read_material
    from frenbrdf.io.patterns import pattern_samples

    truth = read_material(path)
    drawn = pattern_samples(truth, pattern, count, condition_rng(draw, pattern))
    seeded = [(title, model, dataclasses.replace(config, seed=draw)) for title, model, config in columns]
    return reconstruction_row(truth, drawn, seeded, scene, mask)


def measurement_row(material: str, columns: list[tuple[str, Any, Any]], scene: Any, mask: np.ndarray,
                    pattern: str = "merl-bins", count: int = 4000,
                    measured: Path = Path("../shared/data/rgl-measured"), draw: int = 0) -> list[tuple[str, np.ndarray]]:
    """:func:`material_row` of the RGL measurement ``material`` (its ``.bsdf`` in ``measured``): the studies'
    readings of the 19."""
    return material_row(measured / f"{material}.bsdf", columns, scene, mask, pattern, count, draw)
