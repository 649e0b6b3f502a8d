"""A grid of renders for the studies' pictures: one row per case, each image titled, each row labelled."""

from __future__ import annotations

from pathlib import Path

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
