"""``frenbrdf edit``'s work: two measurement files in, the edit between them out, keeping each material.

:func:`edit_files` reads both inputs (:func:`frenbrdf.io.read_samples`), reconstructs each as ``reconstruct``
does (``refine="full"`` by default), and writes the edit that keeps each material
(:func:`frenbrdf.models.editing.edit`: the latent interpolation plus each reconstruction's residual from its
decoding, faded out along t; at t = 0 and 1 each reconstruction itself) at the positions asked for; with
``latent=True`` the plain latent interpolation instead (the model's decodings of ``(1 − t) z_a + t z_b``). The
folder, written whole or not at all (:class:`frenbrdf.io.outputs.OutputFolder`):

``t-0.250.binary``, ``t-0.250.png`` …
    Per position t, the material's MERL table and its render on the metric renderer's sphere.
``strip.png``
    The renders side by side, t rising to the right, each titled with its t; where an input is a whole material (a
    MERL ``.binary``, a ``.bsdf``), its own render frames the strip on its side (a's on the left, b's on the right,
    titled "a, measured" and "b, measured"), set apart by a white gap.
``edit.json``
    The mode, the positions, the inputs, the model, the refinement, each reconstruction's latent, seconds and
    losses, and for a whole-material input the image metrics of the edit's end on its side against the input's
    render (``ends``; :func:`frenbrdf.render.scoring.image_metrics`).
"""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
from tqdm.auto import tqdm

from ..io.atomic import save_json
from ..io.formats import read_samples, write_material
from ..io.merl import FILE_BYTES
from ..io.outputs import OutputFolder, check_free_space
from ..io.patterns import DEFAULT as DEFAULT_PATTERN
from ..io.patterns import pattern as find_pattern
from ..io.samples import Measurements
from ..models.autoencoder import load_model
from ..models.editing import interpolate
from ..models.reconstruct import refine_config
from ..render.figures import titled_row
from ..render.renderer import Scene, material_mask, render, render_linear, save_png

#: The positions ``frenbrdf edit`` writes when none are given.
DEFAULT_T = (0.0, 0.25, 0.5, 0.75, 1.0)
#: The most positions one edit writes (a MERL table of 35 MB and a render each): t every 1/32, as the viewer's slider.
MAX_POSITIONS = 33
#: The largest render (pixels per side): the strip holds every position's, 33 at 1024² about 0.4 GB in float32.
MAX_RESOLUTION = 1024
#: The file names of the folder besides each position's (:func:`position_name`).
FILES = {"strip": "strip.png", "report": "edit.json"}


def position_name(t: float) -> str:
    """The stem of a position's files: ``t-0.250``."""
    return f"t-{t:.3f}"


def check_positions(t) -> list[float]:
    """The positions, rising: each a finite number in [0, 1], no two with the same files (:func:`position_name`)."""
    values = [float(value) + 0.0 for value in t]  # + 0.0 turns −0 into 0: one position, one file name
    if not 1 <= len(values) <= MAX_POSITIONS:
        raise ValueError(f"give 1 to {MAX_POSITIONS} positions t (each writes a 35 MB MERL table), got {len(values)}")
    bad = [value for value in values if not (math.isfinite(value) and 0 <= value <= 1)]
    if bad:
        raise ValueError(f"each position t must be a number in [0, 1] (0 is the first material, 1 the second), got "
                         f"{bad[0]}")
    names = [position_name(value) for value in values]
    if clash := sorted({name for name in names if names.count(name) > 1}):
        raise ValueError(f"positions given twice, or closer than 0.001 (both would write {clash[0]}.*): "
                         f"{sorted(v for v, n in zip(values, names, strict=True) if n == clash[0])}")
    return sorted(values)


def edit_files(source_a: str | os.PathLike, source_b: str | os.PathLike, out_dir: str | os.PathLike,
               t=DEFAULT_T, *, model: str | os.PathLike = "pretrained", latent: bool = False,
               refine: str | None = None, samples: int | None = 4000, pattern: str = DEFAULT_PATTERN, seed: int = 0,
               resolution: int = 256, progress: bool = True, overwrite: bool = False) -> dict:
    """The edit between the materials of two measurement files, written into ``out_dir`` (the module docstring).

    Parameters
    ----------
    source_a, source_b
        CSV, NPZ or ASTM E1392 files of samples, MERL files or RGL ``.bsdf`` (:func:`frenbrdf.io.read_samples`);
        the same file twice is an edit that stays where it is.
    out_dir
        The folder: a new or empty one, or an earlier ``edit``'s, which is replaced; never an input's folder.
    t
        The positions, each in [0, 1]: 0 is ``source_a``'s material, 1 ``source_b``'s.
    model
        ``"pretrained"``, a run folder, a checkpoint or a packed model's folder.
    latent
        The plain latent interpolation instead of the edit that keeps each material.
    refine
        How each input is reconstructed (:data:`frenbrdf.models.reconstruct.BUDGETS`); default ``"full"``, or
        ``"latent"`` with ``latent`` (the latent interpolation's own budget).
    samples, pattern, seed
        As ``reconstruct`` takes them: a whole material's samples given to the model (None: every valid bin), the
        sampling pattern, and the seed of the sampling and the refinement.
    resolution
        Pixels per side of the renders.
    progress
        Show progress bars.
    overwrite
        Write into ``out_dir`` even when it holds entries this command did not write (they are kept).

    Returns
    -------
    dict
        What ``edit.json`` holds.
    """
    positions = check_positions(t)
    if not 8 <= resolution <= MAX_RESOLUTION:
        raise ValueError(f"resolution must be 8 … {MAX_RESOLUTION}, got {resolution}")
    refine = refine or ("latent" if latent else "full")
    config = dataclasses.replace(refine_config(refine), seed=seed, progress=progress)
    find_pattern(pattern)  # an unknown name is refused before anything is read or written
    inputs = (source_a, source_b) if str(model) == "pretrained" else (source_a, source_b, model)
    out = OutputFolder.claim(out_dir, command="edit", inputs=inputs, overwrite=overwrite)
    names = [position_name(value) for value in positions]
    out.check_names([*FILES.values(), *(name + suffix for name in names for suffix in (".binary", ".png"))])
    check_free_space(out.target, len(names) * FILE_BYTES, f"{len(names)} MERL tables")

    measured = [read_samples(source, samples=samples, seed=seed, pattern=pattern) for source in (source_a, source_b)]
    loaded = load_model(model)
    result_a = loaded.reconstruct(measured[0].values, (measured[0].wi, measured[0].wo), refine=config)
    same = os.path.realpath(source_a) == os.path.realpath(source_b)  # one material: reconstructed once
    result_b = result_a if same else loaded.reconstruct(measured[1].values, (measured[1].wi, measured[1].wo),
                                                        refine=config)
    if latent:
        decoded = loaded.decode(interpolate(result_a.z, result_b.z, positions))
        materials: list = [decoded[k] for k in range(len(positions))]
        ends = {"a": loaded.decode(result_a.z), "b": loaded.decode(result_b.z)}
    else:
        edited = loaded.edit(result_a, result_b, positions)
        materials = [edited[k] for k in range(len(positions))]
        ends = {"a": result_a.nbrdf, "b": result_b.nbrdf}

    scene = Scene(resolution=resolution)
    renders = [render(material, scene).astype(np.float32)  # float32: the strip holds them all
               for material in tqdm(materials, desc="render", disable=not progress, leave=False)]
    truths, metrics = {}, {}
    for side, measurement, end, at in (("a", measured[0], ends["a"], 0.0), ("b", measured[1], ends["b"], 1.0)):
        if measurement.truth is None or measurement.table is None:
            continue  # scattered samples: no whole material to render
        truths[side] = render(measurement.truth, scene).astype(np.float32)
        image = renders[positions.index(at)] if at in positions else render(end, scene)
        metrics[side] = _end_metrics(measurement, truths[side], image, scene)

    report = {"mode": "latent" if latent else "kept", "t": positions,
              "inputs": {side: _describe(m, pattern) for side, m in zip("ab", measured, strict=True)},
              "model": {"path": str(model), "method": loaded.method,
                        **({"version": loaded.card.get("version")} if loaded.card else {})},
              "refine": {"budget": refine, **dataclasses.asdict(config)}, "seed": seed,
              "reconstructions": {"a": result_a.summary(), "b": result_b.summary()}, "ends": metrics,
              "files": sorted([*FILES.values(), *(name + suffix for name in names for suffix in (".binary", ".png"))])}
    with out.staged() as staging:
        for name, material, image in tqdm(list(zip(names, materials, renders, strict=True)), desc="tables",
                                          disable=not progress, leave=False):
            write_material(staging / f"{name}.binary", material.merl_table())
            save_png(staging / f"{name}.png", image)
        save_png(staging / FILES["strip"], strip(renders, positions, truths.get("a"), truths.get("b")))
        save_json(staging / FILES["report"], report)
    return report


def strip(renders: list[np.ndarray], positions: list[float], truth_a: np.ndarray | None = None,
          truth_b: np.ndarray | None = None) -> np.ndarray:
    """The renders side by side under their positions (:func:`frenbrdf.render.figures.titled_row`), framed by the
    inputs' own renders where given, each set apart by a white gap of a sixteenth of a render's width."""
    gap = np.ones((renders[0].shape[0], max(1, renders[0].shape[1] // 16), 3), dtype=renders[0].dtype)
    parts = ([truth_a, gap] if truth_a is not None else []) + list(renders) + \
        ([gap, truth_b] if truth_b is not None else [])
    titles = (["a, measured", None] if truth_a is not None else []) + [f"t = {t:g}" for t in positions] + \
        ([None, "b, measured"] if truth_b is not None else [])
    return titled_row(parts, titles)


def _end_metrics(measurement: Measurements, truth: np.ndarray, image: np.ndarray, scene: Scene) -> dict:
    """The image metrics of an end's render against the input's (over the lit material pixels, and its highlights)."""
    from ..render.scoring import highlight_mask, image_metrics

    mask = material_mask(scene)
    return image_metrics(truth, image, mask, highlight_mask(render_linear(measurement.truth, scene), mask))


def _describe(measurement: Measurements, pattern: str) -> dict:
    whole = measurement.table is not None
    return {"path": measurement.source, "kind": measurement.kind, "samples": len(measurement),
            **({"pattern": pattern} if whole else {})}
