"""The editing pass of an evaluation (:mod:`frenbrdf.evaluation.evaluate`): which pairs of materials are blended,
and each method's metrics along each blend."""

from __future__ import annotations

import itertools

import numpy as np
from tqdm.auto import tqdm

from ..render.renderer import Scene, material_mask
from ..render.scoring import edit_metrics


def edit_pairs(n_materials: int, most: int, rng: np.random.Generator) -> list[tuple[int, int]]:
    """Unordered pairs of distinct materials, each at most once: all of them, or ``most`` drawn at random (the
    ``k``-th pair in ``itertools.combinations``' order for each index ``k`` drawn, found without listing them all)."""
    total = n_materials * (n_materials - 1) // 2
    if total <= most:
        return list(itertools.combinations(range(n_materials), 2))
    chosen = np.sort(rng.choice(total, size=most, replace=False))
    rows = np.arange(n_materials)
    starts = rows * n_materials - rows * (rows + 1) // 2  # the index of the pair (a, a + 1), for each a
    first = np.searchsorted(starts, chosen, side="right") - 1
    second = first + 1 + (chosen - starts[first])
    return [(int(a), int(b)) for a, b in zip(first, second, strict=True)]


def edit_rows(models: dict, names: list[str], pairs, latents: dict, edit_truth_linear: dict, weights,
              edit_scene: Scene, *, progress: bool = True) -> dict[str, list[dict]]:
    """Each method's editing rows: every pair at every weight t, from each kind of latent in ``latents`` (by the
    prefix of the metrics they give, then method, then material: the encoder's ``""``, the refined
    ``"refined_"``), against the same blend of the truths' linear renders ``edit_truth_linear``."""
    edit_mask = material_mask(edit_scene)
    edits: dict[str, list[dict]] = {m: [] for m in models}
    with tqdm(total=len(pairs) * len(weights) * len(models), desc="editing", disable=not progress) as bar:
        for a, b in pairs:
            name_a, name_b = names[a], names[b]
            for t in weights:
                for method, model in models.items():
                    row = {"a": name_a, "b": name_b, "t": t}
                    for prefix, by_method in latents.items():
                        metrics = edit_metrics(model, by_method[method][name_a], by_method[method][name_b],
                                               edit_truth_linear[name_a], edit_truth_linear[name_b], t,
                                               edit_scene, edit_mask)
                        row.update({prefix + key: value for key, value in metrics.items()})
                    edits[method].append(row)
                    bar.update()
    return edits
