"""Scoring one model on materials: what every evaluation measures, in one place.

Each material is encoded from N random valid bins of its table (:func:`frenbrdf.io.sampling.sample_bins`; a
measurement is evaluated at them itself, each pair in a random order, :func:`frenbrdf.io.sampling.truth_samples`),
decoded
(or refined at test time, :func:`frenbrdf.models.reconstruct.reconstruct`), rendered and compared with
the render of the true table (:func:`image_metrics`: RMSE, PSNR, SSIM and the colour difference ΔE
over the lit material pixels, and PSNR and ΔE over its highlights, :func:`highlight_mask`), and its frequency
loss measured (:class:`FrequencyMetric`).
:func:`reconstruction_rows` does all of it for a list of MERL files; ``frenbrdf evaluate``
(:mod:`frenbrdf.evaluation.evaluate`), the chart sweeps and the validation renders of training use it.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Literal

import numpy as np
import torch
from tqdm.auto import tqdm

from ..io.formats import read_measured
from ..io.merl import N_BINS
from ..io.patterns import DEFAULT as DEFAULT_PATTERN
from ..io.patterns import pattern_samples
from ..io.sampling import as_table, sample_bins, truth_samples
from ..models.autoencoder import Model
from ..models.losses import FrequencyLoss, FrequencyLossConfig, FrequencyTruth, spectral_distance
from ..models.nbrdf import NBRDF
from ..models.reconstruct import STAGES, Reconstruction, RefineConfig, reconstruct, refine_config
from .renderer import Scene, material_mask, render_linear, tonemap

#: The share of the lit material pixels the highlight metrics are taken over: the brightest in the truth.
HIGHLIGHT_FRACTION = 0.05
#: Rec. 709 luminance of linear RGB: what "brightest" means.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def highlight_mask(truth_linear: np.ndarray, mask: np.ndarray, fraction: float = HIGHLIGHT_FRACTION) -> np.ndarray:
    """The pixels of ``mask`` ``(H, W)`` where the truth's *linear* radiance ``(H, W, 3)`` (its luminance) is in
    its top ``fraction``: where the highlights are, whether or not the display image clamps them.

    It is taken from the linear render, not the display image, because tone mapping clamps at 1: in the
    display image a highlight and its surroundings can tie. Ties at the threshold are all kept.
    """
    mask = np.asarray(mask, dtype=bool)
    if truth_linear.shape[:2] != mask.shape or not mask.any() or not 0 < fraction <= 1:
        raise ValueError(f"a highlight mask needs a linear image {truth_linear.shape} with a non-empty mask of its "
                         f"shape (got {mask.shape}) and a fraction in (0, 1] (got {fraction})")
    luminance = truth_linear @ LUMINANCE
    return mask & (luminance >= np.quantile(luminance[mask], 1 - fraction))


def image_metrics(truth: np.ndarray, prediction: np.ndarray, mask: np.ndarray | None = None,
                  highlight: np.ndarray | None = None) -> dict[str, float]:
    """RMSE, PSNR, SSIM and colour difference ΔE of two display images in [0, 1] ``(H, W, 3)`` over
    the pixels of ``mask`` ``(H, W)`` (default: all; evaluation passes :func:`frenbrdf.render.material_mask`).

    RMSE and PSNR (data range 1) are those of the masked pixels; SSIM is scikit-image's SSIM
    map averaged over them (its 7×7 windows near the silhouette still see some background);
    ``delta_e`` is :func:`delta_e`. With ``highlight`` ``(H, W)`` (:func:`highlight_mask` of the truth's
    linear render) also ``highlight_psnr`` and ``highlight_delta_e``: the same PSNR and ΔE of the display
    images over those pixels only. Measured on the display images like the others, so a highlight that
    both images clamp at 1 agrees there (a few per cent of the top 5 % on MERL materials, a quarter on nickel).
    """
    from skimage.metrics import structural_similarity

    mask = np.ones(truth.shape[:2], dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if mask.shape != truth.shape[:2] or truth.shape != prediction.shape or not mask.any():
        raise ValueError(f"images {truth.shape} and {prediction.shape} need a non-empty mask of shape "
                         f"{truth.shape[:2]}, got {mask.shape}")
    mse = float(np.mean((truth[mask] - prediction[mask]) ** 2))
    psnr = 10 * np.log10(1.0 / mse) if mse > 0 else float("inf")
    _, ssim_map = structural_similarity(truth, prediction, data_range=1.0, channel_axis=-1, full=True)
    metrics = {"rmse": float(np.sqrt(mse)), "psnr": float(psnr), "ssim": float(ssim_map[mask].mean()),
               "delta_e": delta_e(truth, prediction, mask)}
    if highlight is not None:
        highlight = np.asarray(highlight, dtype=bool)
        if highlight.shape != mask.shape or not highlight.any():
            raise ValueError(f"the highlight mask must be non-empty, of shape {mask.shape}; got {highlight.shape}")
        error = float(np.mean((truth[highlight] - prediction[highlight]) ** 2))
        metrics.update(highlight_psnr=float(10 * np.log10(1.0 / error)) if error > 0 else float("inf"),
                       highlight_delta_e=delta_e(truth, prediction, highlight))
    return metrics


def delta_e(truth: np.ndarray, prediction: np.ndarray, mask: np.ndarray) -> float:
    """Mean CIEDE2000 colour difference of two display images in [0, 1] ``(H, W, 3)`` over ``mask``.

    The images are read as sRGB (scikit-image's ``rgb2lab``, D65); ours are gamma 2.2, which
    sRGB's curve follows to within a few per cent. ΔE ≈ 1 is the smallest difference a person
    sees side by side; above ~5 the colours read as different.
    """
    from skimage.color import deltaE_ciede2000, rgb2lab

    return float(deltaE_ciede2000(rgb2lab(truth[mask]), rgb2lab(prediction[mask])).mean())


class FrequencyMetric:
    """L_fre between a true table and a decoded latent (or an NBRDF, e.g. refined), in the model's mapped space.

    The settings are fixed (default: :class:`FrequencyLossConfig`'s), whatever the model was
    trained with, so that values of different models compare. A variant whose spectrum is of
    reflectance (``config.values``) un-maps with each model's own mapping.
    """

    def __init__(self, config: FrequencyLossConfig | None = None):
        config = FrequencyLossConfig() if config is None else config
        self.config = config
        self._parts: dict[int, tuple] = {}
        # The pair every model shares when the values are mapped (the spectrum of reflectance is per mapping).
        self.truth: FrequencyTruth | None
        self.loss: FrequencyLoss | None
        self.truth, self.loss = self.parts(None) if config.values == "mapped" else (None, None)

    def parts(self, model: Model | None) -> tuple[FrequencyTruth, FrequencyLoss]:
        """The truth and the loss for ``model``'s mapping (one pair for every model when the values are mapped)."""
        mapping = None if model is None or self.config.values == "mapped" else model.mapping
        key = id(mapping)
        if key not in self._parts:
            self._parts[key] = (FrequencyTruth(self.config, mapping=mapping), FrequencyLoss(self.config, mapping),
                                mapping)  # the mapping is kept, so that its id is not reused
        return self._parts[key][:2]

    def __call__(self, model: Model, table: np.ndarray, material: np.ndarray | NBRDF) -> float:
        """L_fre of ``material``: a latent ``(latent,)`` of ``model``, or an NBRDF of one material."""
        weights = self.parts(model)[1].degree_weights
        return float(spectral_distance(self.predicted_coefficients(model, material), self.true_coefficients(model, table),
                                       None if weights is None else weights.numpy()))

    def true_coefficients(self, model: Model, table: np.ndarray) -> np.ndarray:
        """The truth L_fre compares with: the table mapped as ``model`` maps, kNN-interpolated onto the SHT grid
        and analysed, ``(S, 3, ncoeff)``."""
        flat = table.reshape(3, N_BINS)
        valid = np.all(flat >= 0, axis=0)
        with np.errstate(invalid="ignore"):
            mapped = model.mapping.forward(np.where(valid, flat, 0.0), model.mapping.reference_bins())
        return self.parts(model)[0].coefficients(np.nan_to_num(mapped).T, valid)

    @torch.no_grad()
    def predicted_coefficients(self, model: Model, material: np.ndarray | NBRDF) -> np.ndarray:
        """The SH coefficients of a decoded latent or an NBRDF at the grid nodes, ``(S, 3, ncoeff)``."""
        params = (material.in_table_order().params if isinstance(material, NBRDF)  # the SHT grid's pairs: a table's
                  else model.network.decoder(torch.from_numpy(material[None].astype(np.float32))))
        return self.parts(model)[1].predicted_coefficients(params)[0].numpy()


def encode_and_render(model: Model, values: np.ndarray, directions, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Encodes samples, decodes and renders the result: (z, display image)."""
    z = model.encode(values, directions)
    return z, tonemap(render_linear(model.decode(z)[0], scene))


def refined_reconstruction(model: Model, samples, scene: Scene,
                           config: RefineConfig) -> tuple[Reconstruction, np.ndarray, float]:
    """Encodes ``samples`` (values, (ω_i, ω_o)) as :func:`frenbrdf.io.sampling.truth_samples` gives them, refines on
    them (:func:`frenbrdf.models.reconstruct.reconstruct`) and renders the result: (reconstruction, display image,
    seconds of the refinement stages, beyond encoding)."""
    result = reconstruct(model, *samples, refine=config)
    seconds = sum(result.timings.get(stage, 0.0) for stage in STAGES if stage != "encode")
    return result, tonemap(render_linear(result.nbrdf, scene)), seconds


@dataclasses.dataclass
class Scored:
    """One method's reconstruction of one material from one pattern's samples (:meth:`Scoring.reconstruct`)."""

    metrics: dict[str, float]
    z: np.ndarray
    image: np.ndarray
    refined: Reconstruction | None = None
    refined_image: np.ndarray | None = None


@dataclasses.dataclass
class Scoring:
    """How :func:`frenbrdf.evaluation.evaluate.evaluate_runs` scores a reconstruction: the scene and its material
    mask, the frequency metric, the test-time refinement (None: the encoder only)."""

    scene: Scene
    mask: np.ndarray
    frequency_metric: FrequencyMetric
    refinement: RefineConfig | None

    def reconstruct(self, model: Model, samples, table: np.ndarray, truth_image: np.ndarray,
                    highlight: np.ndarray) -> Scored:
        """Encodes ``samples`` (values, (ω_i, ω_o)), decodes, renders and compares with the truth's render
        ``truth_image`` (``highlight``: its highlight pixels) and its table; with refinement, refines on the same
        samples and compares again (the keys ``refined_…``)."""
        values, directions = samples
        z, image = encode_and_render(model, values, directions, self.scene)
        metrics = image_metrics(truth_image, image, self.mask, highlight)
        metrics["lfre"] = self.frequency_metric(model, table, z)
        scored = Scored(metrics, z, image)
        if self.refinement is not None:
            result, scored.refined_image, seconds = refined_reconstruction(model, samples, self.scene, self.refinement)
            refined = image_metrics(truth_image, scored.refined_image, self.mask, highlight)
            metrics.update({f"refined_{key}": value for key, value in refined.items()})
            metrics.update(refined_lfre=self.frequency_metric(model, table, result.nbrdf), refine_seconds=seconds)
            scored.refined = result
        return scored


def reconstruction_rows(model: Model, files, *, samples: int = 4000, resolution: int = 256, seed: int = 0,
                        frequency_metric: FrequencyMetric | Literal[False] | None = None, refine: str = "none",
                        progress: bool = True, latents: dict | None = None,
                        pattern: str = DEFAULT_PATTERN) -> list[dict]:
    """Reconstruction metrics of one model on MERL files (e.g. a validation split), one row each.

    Each material is encoded from ``samples`` random valid bins (drawn from ``seed``, in the
    order of ``files``, as :func:`~frenbrdf.evaluation.evaluate.evaluate_runs` draws them; ``pattern``: from
    ``samples`` pairs of that sampling pattern of :mod:`frenbrdf.io.patterns` instead), refined on them with the budget
    ``refine`` (:data:`frenbrdf.models.reconstruct.BUDGETS`; ``"none"``: the encoder alone), decoded,
    rendered and compared with the render of the true table: RMSE, PSNR, SSIM, ΔE, the highlights' PSNR and ΔE
    (:func:`highlight_mask`) and L_fre
    (``frequency_metric``: None for the default one, an instance to reuse across calls, False for no L_fre).
    ``latents``: a dict to receive each material's latent by name (the refined one with ``refine``), for editing.
    """
    refinement = dataclasses.replace(refine_config(refine), seed=seed)
    rng = np.random.default_rng(seed)
    scene = Scene(resolution=resolution)
    mask = material_mask(scene)
    if frequency_metric is None:
        frequency_metric = FrequencyMetric()
    rows = []
    for path in tqdm(list(files), desc="reconstruction", disable=not progress, leave=False):
        path = Path(path)
        truth = read_measured(path)
        table = as_table(truth)
        measured = pattern_samples(truth, pattern, samples, rng, table=table)
        decoded: np.ndarray | NBRDF
        if refine == "none":
            z, image = encode_and_render(model, *measured, scene)
            decoded = z  # what L_fre measures: the latent, or the refined NBRDF itself
        else:
            result, image, _ = refined_reconstruction(model, measured, scene, refinement)
            z, decoded = result.z, (result.nbrdf if refinement.weight_steps else result.z)
        truth_linear = render_linear(truth, scene)
        metrics = image_metrics(tonemap(truth_linear), image, mask, highlight_mask(truth_linear, mask))
        if frequency_metric is not False:
            metrics["lfre"] = frequency_metric(model, table, decoded)
        rows.append({"material": path.stem, **metrics})
        if latents is not None:
            latents[path.stem] = z
    return rows


class ScoringSet:
    """MERL files read once, to score many models on (training's validation renders, every few epochs).

    Each material keeps the encoder's samples, drawn from ``seed`` as :func:`reconstruction_rows` draws
    them, and the display render of its true table; the tables themselves are not kept (no L_fre).
    :meth:`mean_metrics` then costs only the models' encode, decode and render.
    """

    def __init__(self, files, *, samples: int = 4000, resolution: int = 64, seed: int = 0):
        rng = np.random.default_rng(seed)
        self.scene = Scene(resolution=resolution)
        self.mask = material_mask(self.scene)
        self.materials = []
        for path in files:
            truth = read_measured(path)
            table = as_table(truth)
            linear = render_linear(truth, self.scene)
            self.materials.append((truth_samples(truth, sample_bins(table, rng, samples), rng), tonemap(linear),
                                   highlight_mask(linear, self.mask)))

    def mean_metrics(self, model: Model) -> dict[str, float]:
        """RMSE, PSNR, SSIM, ΔE and the highlights' PSNR and ΔE of ``model``'s encoder-only reconstructions,
        averaged over the materials."""
        rows = [image_metrics(truth, encode_and_render(model, values, directions, self.scene)[1], self.mask, highlight)
                for (values, directions), truth, highlight in self.materials]
        return {key: float(np.mean([row[key] for row in rows])) for key in rows[0]}


def edit_metrics(model: Model, z_a: np.ndarray, z_b: np.ndarray, truth_a: np.ndarray, truth_b: np.ndarray, t: float,
                 scene: Scene, mask: np.ndarray) -> dict[str, float]:
    """Image metrics of the edit decode((1 − t)·z_a + t·z_b) against the truth (1 − t)·a + t·b, given the true
    tables' linear renders ``truth_a``, ``truth_b`` (rendering is linear in the BRDF: the blend of the renders is
    the render of the blended table)."""
    linear = (1 - t) * truth_a + t * truth_b
    image = tonemap(render_linear(model.decode((1 - t) * z_a + t * z_b)[0], scene))
    return image_metrics(tonemap(linear), image, mask, highlight_mask(linear, mask))
