"""What a page shows: the inputs of ``frenbrdf view`` read into NBRDFs, and the edit between two of them.

An input is a saved NBRDF (``.pt``), a published Keras NBRDF (``.h5``), a ``reconstruct`` result folder
(``material.pt`` and the latent in ``reconstruction.json``), or a measurement (MERL ``.binary``, RGL ``.bsdf``),
which the page shows as its fit by the packaged model (``reconstruct``'s ``full`` refinement from 4000 samples):
a fit of 64-wide layers is about 20 KB of weights, the MERL table itself 35 MB in float64.

Two inputs get an edit slider t ∈ [0, 1] (:class:`Edit`), in one of two modes:

``latent``
    The latent interpolation: the model's decoding of ``(1 − t) z_a + t z_b``. Its ends are the model's
    decodings of the two latents, not the materials where those were refined beyond the latent space.
``kept``
    The edit that keeps each material: the latent interpolation plus each material's residual from its own
    decoding, faded out along t, in the model's mapped space (y = ln((f + ε) / (f_ref + ε))):
    ``y_t = D(z_t) + (1 − t) (y_a − D(z_a)) + t (y_b − D(z_b))``. At t = 0 and 1 it is the materials
    themselves. Offered where a material differs from its decoding (refined weights).

The page holds the decodings at :data:`KEYFRAMES` values of t (1/32 apart) and the slider steps between them.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from ...models.mapping import LogRelativeMapping
from ...models.nbrdf import NBRDF

#: The edit's positions: t = k / (KEYFRAMES − 1), each decoded exactly (the slider steps by 1/32).
KEYFRAMES = 33
#: Samples a measurement (or an NBRDF that needs a latent) is given to the model, as ``reconstruct`` does.
SAMPLES = 4000
#: What ``view`` reads, for messages.
SUPPORTED = ("a saved NBRDF (.pt), a Keras NBRDF (.h5), a reconstruct result folder, a MERL .binary file or an "
             "RGL .bsdf measurement")


@dataclass
class Material:
    """One input, ready for a page."""

    nbrdf: NBRDF
    """The material (one NBRDF)."""
    name: str
    """What the page calls it (the file's or folder's name)."""
    origin: str
    """Where it came from, in words (the path, and how it was made)."""
    z: np.ndarray | None = None
    """Its latent in :attr:`model_key`'s model, where it has one."""
    model_key: str | None = None
    """The model its latent belongs to (``"pretrained"``, or a run folder's path)."""


@dataclass
class Edit:
    """The edit between two materials: the decoded keyframes and, where a material was refined, the kept mode."""

    a: Material
    b: Material
    keyframes: list[NBRDF]
    """The model's decodings at t = k / (KEYFRAMES − 1)."""
    mapping: LogRelativeMapping
    """The model's mapping: the space the kept mode adds in."""
    modes: tuple[str, ...] = field(default=("latent",))
    """``("latent",)``, or ``("kept", "latent")`` where a material differs from its decoding (the first is the
    default)."""

    @staticmethod
    def index(t: float) -> int:
        """The keyframe a position t ∈ [0, 1] shows (the nearest)."""
        if not 0 <= t <= 1:
            raise ValueError(f"the edit position t must lie in [0, 1], got {t}")
        return int(round(t * (KEYFRAMES - 1)))

    def terms(self, t: float, mode: str) -> list[tuple[NBRDF, float]]:
        """The material at t as weighted NBRDFs, summed in :attr:`mapping`'s space (:func:`combined`)."""
        if mode not in self.modes:
            raise ValueError(f"this edit offers the modes {self.modes}, not {mode!r}")
        k = self.index(t)
        t = k / (KEYFRAMES - 1)
        terms = [(self.keyframes[k], 1.0)]
        if mode == "kept":
            # At the ends the keyframe is the decoding itself: drop both rather than add and subtract it.
            for material, own, weight in ((self.a, self.keyframes[0], 1 - t), (self.b, self.keyframes[-1], t)):
                if weight:
                    terms += [(material.nbrdf, weight), (own, -weight)]
            if k in (0, KEYFRAMES - 1):
                terms = [(self.a.nbrdf if k == 0 else self.b.nbrdf, 1.0)]
        return terms


def combined(terms: list[tuple[NBRDF, float]], mapping: LogRelativeMapping):
    """``brdf(wi, wo) -> (..., 3)``: the sum of the terms' reflectance, each taken into ``mapping``'s space
    (y = forward(f), f clamped as every NBRDF clamps it), weighted, and mapped back; what the page computes
    per pixel, in float64 (the page in float32)."""
    if len(terms) == 1 and terms[0][1] == 1.0:
        return terms[0][0]

    def brdf(wi, wo):
        y = sum(weight * mapping.forward(nbrdf(wi, wo), mapping.reference) for nbrdf, weight in terms)
        return mapping.inverse(y, mapping.reference)

    return brdf


def read_material(path: str | os.PathLike, *, model=None, progress: bool = False) -> Material:
    """Reads one input of ``view`` (see the module docstring).

    ``model``: the model that fits a measurement (default: the packaged one). Raises FileNotFoundError or
    ValueError naming the file and what was expected.
    """
    from ...io import formats
    from ...io.paths import input_file

    path = Path(path)
    if path.is_dir():
        return _result_folder(path)
    path = input_file(path, "material file")
    try:
        entry = formats.format_of(path, ("measurement", "nbrdf"), "view")
    except ValueError:
        raise ValueError(f"{path}: unknown format; view reads {SUPPORTED}") from None
    if entry.role == "measurement":
        return _fit_measurement(path, model, progress)
    nbrdf = NBRDF.from_weights(entry.read(path))
    return Material(nbrdf, path.stem, f"{path} ({entry.holds}, {_describe(nbrdf)})")


def _describe(nbrdf: NBRDF) -> str:
    widths = [int(p.shape[1]) for p in nbrdf.params[0::2]]
    n = sum(int(p[0].numel()) for p in nbrdf.params)
    return f"6→{'→'.join(map(str, widths))}, {n} weights" + (", ordered" if nbrdf.ordered else "")


def _result_folder(folder: Path) -> Material:
    from ...io.jsonfile import read_json
    from ...io.nbrdf import read_nbrdf

    report_path, nbrdf_path = folder / "reconstruction.json", folder / "material.pt"
    if not report_path.is_file() or not nbrdf_path.is_file():
        raise ValueError(f"{folder}: a folder, but not a reconstruct result (it lacks reconstruction.json or "
                         f"material.pt); view reads {SUPPORTED}")
    report = read_json(report_path, "reconstruction report")
    try:
        z = np.asarray(report["z"], dtype=np.float64)
        model_key = str(report["model"]["path"])
        source, refine = report["input"]["path"], report["refine"]["budget"]
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"{report_path}: not a reconstruct report (missing or wrong {error})") from None
    if z.ndim != 1 or not np.all(np.isfinite(z)):
        raise ValueError(f"{report_path}: its latent z is not a finite vector")
    nbrdf = NBRDF.from_weights(read_nbrdf(nbrdf_path))
    model_name = "the packaged model" if model_key == "pretrained" else f"the model {model_key}"
    return Material(nbrdf, folder.name, f"reconstructed in {folder}/ from {source} by {model_name} "
                    f"(refine {refine}; {_describe(nbrdf)})", z, model_key)


def _fit_measurement(path: Path, model, progress: bool) -> Material:
    """A MERL table or .bsdf measurement as the packaged model's fit (``reconstruct``'s ``full`` refinement)."""
    from ...io.formats import read_samples
    from ...models.autoencoder import Model

    model = Model.pretrained() if model is None else model
    measured = read_samples(path, samples=SAMPLES, seed=0)  # what reconstruct reads of the file
    result = model.reconstruct(measured.values, (measured.wi, measured.wo), refine=_refine("full", progress))
    what = "RGL measurement" if measured.kind == "bsdf" else "MERL table"
    return Material(result.nbrdf, path.stem, f"{path} (a {what}; shown as its fit by the packaged model from "
                    f"{SAMPLES} samples, refine full: {_describe(result.nbrdf)})", result.z, "pretrained")


def _refine(budget: str, progress: bool):
    import dataclasses

    from ...models.reconstruct import refine_config

    return dataclasses.replace(refine_config(budget), seed=0, progress=progress)


def nbrdf_samples(nbrdf: NBRDF, n: int = SAMPLES, seed: int = 0) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """An NBRDF's values at ``n`` random MERL bins above the horizon (what the encoder reads of a table)."""
    from ...io.merl import merl_above_horizon, merl_bin_directions

    rng = np.random.default_rng(seed)
    bins = rng.choice(np.flatnonzero(merl_above_horizon()), size=n, replace=False)
    wi, wo = (d.reshape(-1, 3)[bins] for d in merl_bin_directions())
    return nbrdf(wi, wo), (wi, wo)


def make_edit(a: Material, b: Material, *, model=None, progress: bool = False) -> Edit:
    """The edit between two materials in one model's latent space.

    ``model``: a :class:`frenbrdf.Model`; by default the model of ``a``'s latent (a result folder's), else
    of ``b``'s, else the packaged one. A material with no latent in that model is encoded (its samples at
    4000 MERL bins, the latent refined: ``reconstruct``'s ``latent`` budget).
    """
    from ...models.autoencoder import interpolate, load_model

    key = None
    if model is None:
        key = a.model_key or b.model_key or "pretrained"
        try:
            model = load_model(key)
        except (OSError, ValueError) as error:
            raise ValueError(f"the edit needs the model the latents belong to, {key}, which cannot be loaded "
                             f"({error}); pass another with --model") from None
    latents = []
    for material in (a, b):
        if material.z is not None and material.model_key == key and len(material.z) == model.config.encoder.latent:
            latents.append(material.z)
        else:
            values, directions = nbrdf_samples(material.nbrdf)
            latents.append(model.reconstruct(values, directions, refine=_refine("latent", progress)).z)
            material.origin += f"; its latent for the edit encoded from {SAMPLES} of its values (refine latent)"
    ts = np.linspace(0.0, 1.0, KEYFRAMES)
    decoded = model.decode(interpolate(latents[0], latents[1], ts))
    keyframes = [decoded[k] for k in range(KEYFRAMES)]
    refined = any(not _same(m.nbrdf, own) for m, own in ((a, keyframes[0]), (b, keyframes[-1])))
    return Edit(a, b, keyframes, model.mapping, ("kept", "latent") if refined else ("latent",))


def _same(x: NBRDF, y: NBRDF) -> bool:
    """The same network and mapping (a material that is its own decoding)."""
    return x.ordered == y.ordered and len(x.params) == len(y.params) \
        and all(p.shape == q.shape and torch.equal(p, q) for p, q in zip(x.params, y.params, strict=True)) \
        and mapping_state(x.mapping) == mapping_state(y.mapping)


def mapping_state(mapping: LogRelativeMapping) -> tuple:
    """A per-channel mapping as numbers the page uses: f_ref (3), ε, c. A per-bin f_ref is refused."""
    if mapping.per_bin:
        raise ValueError("this NBRDF's mapping has a reference per MERL bin (17.5 MB); the viewer takes NBRDFs "
                         "with a reference per channel (every packaged, fitted and published one)")
    return (*(float(v) for v in mapping.reference), mapping.epsilon, mapping.offset)

