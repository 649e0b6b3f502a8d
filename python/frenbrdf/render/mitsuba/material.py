"""Materials as the plugin sees them: loading, and handles for materials held in memory."""

from __future__ import annotations

import functools
import itertools
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .sampling import SamplingMixture, fit_sampling
from .variants import PLUGIN_NAME

if TYPE_CHECKING:
    from ...io.bsdf import MeasuredBSDF
    from ...models.nbrdf import NBRDF


@dataclass(eq=False)
class Material:
    """A material in a form the plugin can evaluate (numpy side, independent of the variant).

    Use :func:`load_material` to build one from a path, an NBRDF or a table.
    """

    kind: str
    """``"nbrdf"``, ``"merl"`` or ``"measured"`` (an RGL ``.bsdf`` measurement)."""
    name: str
    """For messages and the plugin's ``to_string``."""
    layers: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)
    """NBRDF: (weight ``(out, in)``, bias ``(out,)``) per layer, float32; ReLU between layers."""
    epsilon: float = 0.0
    """NBRDF: the mapping's ε."""
    offset: float = 0.0
    """NBRDF: the mapping's offset c (f = (f_ref + ε)(exp(y) − c) − ε)."""
    reference: np.ndarray | None = None
    """NBRDF: f_ref, ``(3,)`` or a MERL-shaped table ``(3, 90, 90, 180)``."""
    table: np.ndarray | None = None
    """MERL: the table ``(3, 90, 90, 180)`` in physical units, missing bins negative."""
    nbrdf: NBRDF | None = None
    """NBRDF: the :class:`frenbrdf.NBRDF` itself (numpy evaluation)."""
    measurement: MeasuredBSDF | None = None
    """Measured: the :class:`frenbrdf.io.bsdf.MeasuredBSDF` (numpy evaluation, by the Rust core)."""
    ordered: bool = False
    """Whether it tells the two orders of a pair apart (an ordered NBRDF, :attr:`frenbrdf.NBRDF.ordered`, or a
    measurement): then the plugin evaluates it with the light's direction first, as the metric renderer does."""

    def brdf(self, wi, wo) -> np.ndarray:
        """Reference (numpy) evaluation: reflectance at direction pairs ``(..., 3)`` → ``(..., 3)``, ≥ 0."""
        if self.kind == "nbrdf":
            assert self.nbrdf is not None
            return self.nbrdf(wi, wo)
        if self.kind == "measured":
            assert self.measurement is not None
            return self.measurement(wi, wo)
        from ...io.merl import merl_lookup_directions

        return np.maximum(merl_lookup_directions(self.table, wi, wo, method="trilinear"), 0.0)

    @functools.cached_property
    def sampling(self) -> SamplingMixture:
        """The fitted importance-sampling mixture (computed once)."""
        return fit_sampling(self.brdf)

    @functools.cached_property
    def interleaved(self) -> np.ndarray:
        """The table (MERL) or the reference table (NBRDF) as float32 ``(N_BINS, 3)``."""
        source = self.table if self.kind == "merl" else self.reference
        assert source is not None
        return np.ascontiguousarray(source.reshape(3, -1).T, dtype=np.float32)


def material_from_nbrdf(nbrdf, name: str = "nbrdf") -> Material:
    """A :class:`Material` for one :class:`frenbrdf.NBRDF` (``len(nbrdf) == 1``)."""
    from ...models.nbrdf import NBRDF

    if not isinstance(nbrdf, NBRDF):
        raise TypeError(f"expected an NBRDF, got {type(nbrdf).__name__}")
    if len(nbrdf) != 1:
        raise ValueError(f"this NBRDF holds {len(nbrdf)} materials; pass one, e.g. nbrdf[0]")
    params = [p[0].numpy().astype(np.float32) for p in nbrdf.params]
    layers = list(zip(params[0::2], params[1::2], strict=True))
    reference = np.asarray(nbrdf.mapping.reference, dtype=np.float64)
    return Material("nbrdf", name, layers=layers, epsilon=float(nbrdf.mapping.epsilon),
                    offset=float(nbrdf.mapping.offset), reference=reference, nbrdf=nbrdf, ordered=nbrdf.ordered)


def material_from_table(table, name: str = "merl") -> Material:
    """A :class:`Material` for a MERL table ``(3, 90, 90, 180)`` in physical units."""
    from ...io.merl import SHAPE

    table = np.asarray(table, dtype=np.float64)
    if table.shape != SHAPE:
        raise ValueError(f"a MERL table must have shape {SHAPE}, got {table.shape}")
    if not np.all(np.isfinite(table)):
        raise ValueError(f"{name}: the MERL table holds NaN or inf values")
    return Material("merl", name, table=table)


def material_from_measurement(measurement, name: str | None = None) -> Material:
    """A :class:`Material` for a measurement read by :func:`frenbrdf.read_bsdf`, evaluated as it is (never
    through a quantised table) and light first: the measurements are not reciprocal near grazing."""
    from ...io.bsdf import MeasuredBSDF

    if not isinstance(measurement, MeasuredBSDF):
        raise TypeError(f"expected a MeasuredBSDF (frenbrdf.read_bsdf), got {type(measurement).__name__}")
    return Material("measured", name or measurement.name, measurement=measurement, ordered=True)


def load_material(material) -> Material:
    """Any supported material → :class:`Material`.

    Parameters
    ----------
    material
        A :class:`frenbrdf.NBRDF` (one material); a MERL table array; a measurement
        (:func:`frenbrdf.read_bsdf`); an NBRDF's weights; a path to a MERL ``.binary`` file, to an RGL ``.bsdf``,
        to a saved NBRDF ``.pt`` or to a published Keras NBRDF ``.h5`` (any :func:`frenbrdf.io.read_material`
        reads); a :func:`material_handle`; or a :class:`Material`.

    Raises
    ------
    FileNotFoundError
        The path does not exist.
    ValueError
        The file is none of the supported formats (the message names it).
    TypeError
        Anything else.
    """
    from ...io.bsdf import MeasuredBSDF
    from ...models.nbrdf import NBRDF, as_brdf

    material = as_brdf(material)  # an NBRDF's weights as their NBRDF
    if isinstance(material, Material):
        return material
    if isinstance(material, NBRDF):
        return material_from_nbrdf(material)
    if isinstance(material, MeasuredBSDF):
        return material_from_measurement(material)
    if isinstance(material, np.ndarray):
        return material_from_table(material)
    if isinstance(material, str) and material in _HANDLES:
        return _HANDLES[material]
    if isinstance(material, (str, os.PathLike)):
        return _load_file(Path(material))
    raise TypeError(f"cannot render a {type(material).__name__}: pass an NBRDF, a MERL table, a measurement, or a "
                    "path to a MERL file, an RGL .bsdf, a saved NBRDF or a Keras NBRDF .h5")


def _load_file(path: Path) -> Material:
    """A material file (any :func:`frenbrdf.io.read_material` reads) → :class:`Material`."""
    from ...io.bsdf import MeasuredBSDF
    from ...io.formats import read_material
    from ...models.nbrdf import as_brdf

    loaded = as_brdf(read_material(path))
    if isinstance(loaded, MeasuredBSDF):
        return material_from_measurement(loaded)  # named by its file's stem
    if isinstance(loaded, np.ndarray):
        return material_from_table(loaded, name=path.stem)
    return material_from_nbrdf(loaded, name=path.stem)



_HANDLES: dict[str, Material] = {}
_OWNERS: dict[str, object] = {}  # handle → the object it was made from (identity look-up)
_COUNTER = itertools.count()


def material_handle(material) -> str:
    """Keeps a material in memory under a name the plugin's ``material`` property accepts.

    The same in-memory object (NBRDF, table, :class:`Material`) always gets the same
    handle; it is read when the handle is made. The material stays referenced until
    :func:`release_handle` (scenes already loaded keep their own reference).
    """
    if isinstance(material, str) and material in _HANDLES:
        return material
    in_memory = not isinstance(material, (str, os.PathLike))
    if in_memory:
        for handle, owner in _OWNERS.items():
            if owner is material:
                return handle
    loaded = load_material(material)
    handle = f"frenbrdf:{loaded.kind}:{loaded.name}:{next(_COUNTER)}"
    _HANDLES[handle] = loaded
    if in_memory:
        _OWNERS[handle] = material
    return handle


def release_handle(handle: str) -> None:
    """Forgets a handle from :func:`material_handle` (scenes already loaded keep working)."""
    _HANDLES.pop(handle, None)
    _OWNERS.pop(handle, None)


def bsdf_dict(material, *, lookup: str = "trilinear", sampling: str = "fitted") -> dict:
    """The scene dictionary of a ``frenbrdf`` BSDF for any supported material.

    Files are referenced by path; in-memory materials through :func:`material_handle`.
    """
    entry = {"type": PLUGIN_NAME, "lookup": lookup, "sampling": sampling}
    if isinstance(material, (str, os.PathLike)) and not (isinstance(material, str) and material in _HANDLES):
        entry["filename"] = os.fspath(material)
    else:
        entry["material"] = material_handle(material)
    return entry

