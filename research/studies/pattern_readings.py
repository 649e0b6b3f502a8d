"""Materials read through sampling patterns, as the encoder studies read them: each material's truth rendered once,
then its samples through each pattern and draw (encoder-choice, second-look, repeated-look); and those readings
reconstructed by several models and scored."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from frenbrdf.io.formats import read_measured
from frenbrdf.io.patterns import pattern_samples
from frenbrdf.io.sampling import as_table
from frenbrdf.models.reconstruct import reconstruct, refine_config
from frenbrdf.render import Scene, material_mask, render_linear, tonemap
from frenbrdf.render.scoring import highlight_mask, image_metrics


@dataclass
class Reading:
    """One material's samples through one pattern and draw, and what its renders are judged against."""

    material: str
    pattern: str
    draw: int
    values: np.ndarray
    directions: tuple[np.ndarray, np.ndarray]
    truth_image: np.ndarray
    highlight: np.ndarray

    def metrics(self, image: np.ndarray, mask: np.ndarray) -> dict[str, float]:
        """A display render's metrics against the truth's (PSNR, ΔE, ...)."""
        return image_metrics(self.truth_image, image, mask, self.highlight)


def readings(materials: list[Path], patterns, draws, count: int, scene: Scene, mask: np.ndarray) -> Iterator[Reading]:
    """Every material (MERL tables or measurements) through every pattern at ``count`` samples, for each draw; the
    samples of (draw, pattern, material) come from a generator of those three, the same in every study."""
    for path in tqdm(materials, desc="materials"):
        truth = read_measured(path)
        table = as_table(truth) if isinstance(truth, np.ndarray) else None
        truth_linear = render_linear(truth, scene)
        truth_image, highlight = tonemap(truth_linear), highlight_mask(truth_linear, mask)
        for draw in draws:
            for p, name in enumerate(patterns):
                rng = np.random.default_rng([draw, p, sum(map(ord, path.stem))])
                values, directions = pattern_samples(truth, name, count, rng, table=table)
                yield Reading(path.stem, name, draw, values, directions, truth_image, highlight)


def reconstruction_rows(models: dict, label: str, materials: list[Path], patterns, draws, count: int,
                        budgets) -> list[dict]:
    """Every reading of :func:`readings` reconstructed by each of ``models`` (``{key: Model}``) by each budget
    (``none``: the encoder alone; refinement seeded by the draw), its render (128²) scored against the truth's: one
    row each, with the model's key under ``label``."""
    scene = Scene(resolution=128)
    mask = material_mask(scene)
    rows = []
    for reading in readings(materials, patterns, draws, count, scene, mask):
        for budget in budgets:
            config = dataclasses.replace(refine_config(budget), seed=reading.draw)
            for key, model in models.items():
                result = reconstruct(model, reading.values, reading.directions, refine=config)
                metrics = reading.metrics(tonemap(render_linear(result.nbrdf, scene)), mask)
                rows.append({"material": reading.material, "pattern": reading.pattern, "draw": reading.draw,
                             "budget": budget, label: key, "psnr": metrics["psnr"], "delta_e": metrics["delta_e"]})
    return rows
