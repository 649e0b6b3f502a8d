"""``frenbrdf reconstruct``'s work: a measurement file in, a result folder out.

:func:`reconstruct_file` reads the samples (:func:`frenbrdf.io.read_samples`), loads the model
(a run folder, a checkpoint, or the packaged one), reconstructs and refines
(:func:`frenbrdf.models.reconstruct.reconstruct`), computes everything, and only then writes the
folder, all of it or nothing:

``material.pt``
    The NBRDF (:func:`frenbrdf.io.write_material`), which ``frenbrdf render`` and the
    Mitsuba plugin load.
``material.binary``
    Its MERL table.
``render.png``
    The reconstruction on the metric renderer's sphere; with a MERL input also
    ``truth.png`` and ``comparison.png`` (the truth beside the reconstruction, titled with the render PSNR and ΔE
    where the renders are at least about 130 px wide: ``frenbrdf.render.figures.titled_row``);
    a ``.bsdf`` truth renders as measured.
``spectrum.png``
    With a MERL or ``.bsdf`` input: the per-degree power spectra of the truth and of the reconstruction and the
    error's, per θ_h slice (:mod:`frenbrdf.evaluation.spectrum`): where the reconstruction loses its frequencies.
``reconstruction.json``
    The input (with a MERL or ``.bsdf`` input, the sampling pattern: :mod:`frenbrdf.io.patterns`), the model,
    the refinement, the latent, seconds and loss per stage, and with a MERL or ``.bsdf`` input the image metrics
    against the truth's render (RMSE, PSNR, SSIM, ΔE over the lit material pixels and PSNR, ΔE over its
    highlights, :func:`frenbrdf.render.scoring.image_metrics`), L_fre, and the spectrum's error by degree band
    (``spectrum``).
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np

from ..io.astm import SUFFIX as ASTM_SUFFIX
from ..io.atomic import save_json
from ..io.formats import read_samples, write_material
from ..io.outputs import OutputFolder
from ..io.patterns import DEFAULT as DEFAULT_PATTERN
from ..io.patterns import pattern as find_pattern
from ..io.samples import Measurements
from ..models.autoencoder import Model, load_model
from ..models.coverage import coverage_summary
from ..models.reconstruct import Reconstruction, refine_config
from ..render.figures import titled_row
from ..render.renderer import Scene, material_mask, render, save_png

#: The file names of the result folder.
FILES = {"nbrdf": "material.pt", "merl": "material.binary", "render": "render.png", "truth": "truth.png",
         "comparison": "comparison.png", "spectrum": "spectrum.png", "report": "reconstruction.json"}


#: The latent stage's coverage weights (:attr:`frenbrdf.models.reconstruct.RefineConfig.coverage_k`) where
#: :func:`reconstruct_file` knows the samples come from a device, with ``refine="latent"``: +1.96 and +1.86 dB
#: through five device patterns on two sets of 45 unseen procedural materials
#: (research/results/latent-coverage/README.md); random bins, where the weights cost 0.23 dB, and files of samples
#: that may be anything stay unweighted.
DEVICE_COVERAGE_K = 32


def reconstruct_file(source: str | os.PathLike, out_dir: str | os.PathLike, *, model: str | os.PathLike = "pretrained",
                     samples: int | None = 4000, refine: str = "full", seed: int = 0, resolution: int = 256,
                     progress: bool = True, overwrite: bool = False, width: int | None = None,
                     reciprocal: bool = False, pattern: str = DEFAULT_PATTERN, coverage_k: int | None = None) -> dict:
    """Reconstructs the material of a measurement file into ``out_dir`` (see the module docstring).

    Parameters
    ----------
    source
        A CSV, NPZ or ASTM E1392 (``.astm``) file of samples, a MERL file or an RGL ``.bsdf``
        (:func:`frenbrdf.io.read_samples`).
    out_dir
        The result folder, created whole or replacing an earlier result (:func:`check_out` says which
        folders may be written; nothing is computed when this one may not).
    model
        ``"pretrained"``, a run folder or a checkpoint.
    samples
        MERL or ``.bsdf`` input: random valid bins given to the model (None: all), or pairs of ``pattern``.
    refine
        ``"none"``, ``"latent"`` or ``"full"`` (:data:`frenbrdf.models.reconstruct.BUDGETS`).
    seed
        Seeds the MERL sampling (or the pattern) and the refinement's mini-batches.
    resolution
        Pixels per side of the renders (``render.png``, and the truth's that the metrics compare with).
    progress
        Show progress bars.
    width
        ``refine="full"`` only: the least hidden width of the refined NBRDF
        (:attr:`frenbrdf.models.reconstruct.RefineConfig.width`; None: the budget's, 64 for ``full``).
    reciprocal
        ``refine="full"``: keep the refined NBRDF reciprocal even when the samples hold both orders of pairs
        (:attr:`frenbrdf.models.reconstruct.RefineConfig.keep_order` False).
    overwrite
        Write into ``out_dir`` even when it holds entries this function did not write (they are kept).
    pattern
        MERL or ``.bsdf`` input: the sampling pattern (:data:`frenbrdf.io.patterns.PATTERNS`: the device imitated),
        recorded in the report's ``input``; ``merl-bins``, the default, draws random valid bins.
    coverage_k
        The latent stage weighs samples by how thinly they cover their region
        (:attr:`frenbrdf.models.reconstruct.RefineConfig.coverage_k`; 0: alike). None (the default):
        :data:`DEVICE_COVERAGE_K` with ``refine="latent"`` where the samples are known to come from a device (a
        ``pattern`` other than ``merl-bins``, or an ``.astm`` file), else 0.

    Returns
    -------
    dict
        What ``reconstruction.json`` holds.
    """
    config = dataclasses.replace(refine_config(refine), seed=seed, progress=progress)
    if width is not None:
        config = dataclasses.replace(config, width=width)  # checked before anything is read or written
    if reciprocal:
        config = dataclasses.replace(config, keep_order=False)
    if coverage_k is None:
        from_device = pattern != DEFAULT_PATTERN or os.fspath(source).lower().endswith(ASTM_SUFFIX)
        # Judged for `latent` only: `full`'s shorter latent stage before its weight fit was not measured with it.
        coverage_k = DEVICE_COVERAGE_K if from_device and refine == "latent" else 0
    config = dataclasses.replace(config, coverage_k=coverage_k)  # checked before anything is read or written
    find_pattern(pattern)  # an unknown name is refused before anything is read or written
    out = check_out(source, out_dir, model, overwrite=overwrite)
    measurements = read_samples(source, samples=samples, seed=seed, pattern=pattern)
    loaded = load_model(model)
    result = loaded.reconstruct(measurements.values, (measurements.wi, measurements.wo), refine=config)
    scene = Scene(resolution=resolution)
    images = {"render": render(result.nbrdf, scene)}
    whole = measurements.table is not None  # a whole material, sampled here; not scattered samples
    report = {"input": {"path": str(source), "kind": measurements.kind, "samples": len(measurements),
                        **({"pattern": pattern} if whole else {})},
              "model": {"path": str(model), "method": loaded.method, **({"version": loaded.card.get("version")}
                                                                          if loaded.card else {})},
              "refine": {"budget": refine, **dataclasses.asdict(config)}, "seed": seed, **result.summary(),
              "ordered": result.nbrdf.ordered, "coverage": coverage_summary(measurements.wi, measurements.wo)}
    if measurements.truth is not None and measurements.table is not None:  # a whole material, not scattered samples
        images["truth"] = render(measurements.truth, scene)
        report["metrics"] = truth_metrics(loaded, result, measurements, images["truth"], images["render"], scene)
        from ..evaluation.spectrum import SpectrumSummary

        spectrum = SpectrumSummary()
        spectrum.add(measurements.table, {"reconstruction": result.nbrdf})
        report["spectrum"] = spectrum.summary()
    report["files"] = sorted(FILES[name] for name in ["nbrdf", "merl", "report", *images,
                                                      *(["comparison", "spectrum"] if "truth" in images else [])])
    table = result.nbrdf.merl_table()
    _write_folder(out, result, table, images, report, spectrum if "spectrum" in report else None)
    return report


def truth_metrics(model: Model, result: Reconstruction, measurements: Measurements, truth_image: np.ndarray,
                  image: np.ndarray, scene: Scene) -> dict[str, float]:
    """RMSE, PSNR, SSIM and ΔE of the renders over the lit material pixels, PSNR and ΔE over the truth's highlights
    (:func:`frenbrdf.render.scoring.highlight_mask`), and L_fre against the true table."""
    from ..render.renderer import render_linear
    from ..render.scoring import FrequencyMetric, highlight_mask, image_metrics

    if measurements.table is None:
        raise ValueError(f"{measurements.source}: scattered samples have no truth to compare with")
    mask = material_mask(scene)
    metrics = image_metrics(truth_image, image, mask, highlight_mask(render_linear(measurements.truth, scene), mask))
    metrics["lfre"] = FrequencyMetric()(model, measurements.table, result.nbrdf)
    return metrics


def check_out(source: str | os.PathLike, out_dir: str | os.PathLike, model: str | os.PathLike = "pretrained", *,
              overwrite: bool = False) -> OutputFolder:
    """Where :func:`reconstruct_file` may write, checked before any work (:class:`frenbrdf.io.outputs.OutputFolder`):
    a new or empty folder, or an earlier result folder of ``reconstruct``; never the folder of the input or of
    the model; a folder holding other entries only with ``overwrite`` (they are kept)."""
    inputs = (source,) if str(model) == "pretrained" else (source, model)
    out = OutputFolder.claim(out_dir, command="reconstruct", inputs=inputs, overwrite=overwrite)
    out.check_names(FILES.values())
    return out


def _write_folder(out: OutputFolder, result: Reconstruction, table: np.ndarray, images: dict, report: dict,
                  spectrum=None) -> None:
    """Writes the result into a hidden folder, then puts it in place (:meth:`OutputFolder.staged`): an earlier
    result is replaced, never mixed with this one, and nothing else in the folder is touched."""
    with out.staged() as staging:
        write_material(staging / FILES["nbrdf"], result.nbrdf.weights())
        write_material(staging / FILES["merl"], table)
        for name, image in images.items():
            save_png(staging / FILES[name], image)
        if "truth" in images:  # a whole material, its truth rendered beside
            metrics = report["metrics"]
            titles = ["measured (truth)", f"reconstruction: {metrics['psnr']:.1f} dB, ΔE {metrics['delta_e']:.2f}"]
            save_png(staging / FILES["comparison"], titled_row([images["truth"], images["render"]], titles))
        if spectrum is not None:
            spectrum.write(staging / FILES["spectrum"])
        save_json(staging / FILES["report"], report)
