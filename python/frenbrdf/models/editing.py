"""Editing: the latent interpolation (:func:`interpolate`), and edits that keep each material (:func:`edit`), the
latent interpolation plus what refinement added beyond the decoder.

A ``full`` reconstruction (:func:`frenbrdf.models.reconstruct.reconstruct`) is an NBRDF whose weights were refined
beyond the decoding of its latent z, several dB nearer a real measurement's render than ``model.decode(z)``
(docs/usage.md). An edit along the latent interpolation alone (:func:`interpolate`, then :meth:`frenbrdf.Model.decode`)
starts and ends at those decodings, and so throws that away. :func:`edit` keeps it: in the model's mapped space
y = ln((f + ε) / (f_ref + ε)) (:mod:`frenbrdf.models.mapping`), with z_t = (1 − t) z_a + t z_b,

    y_t = D(z_t) + (1 − t) (y_a − D(z_a)) + t (y_b − D(z_b)),

D the decoding, y_a and y_b the two materials: the latent path carries each material's residual from its own
decoding, faded out along t. At t = 0 and 1 it is each material itself; between them it moves as smoothly as the
decoder does; with no residual (a ``latent`` reconstruction) it is the plain latent interpolation. The sum is
evaluated as ``(1 − t) y_a + t y_b + (D(z_t) − (1 − t) D(z_a) − t D(z_b))``, which at t = 0 and 1 adds an exact 0
to the material (each latent is decoded alone, so D(z_t) at an end is D(z_a) bit for bit): the ends are the
materials up to the logarithm's round trip (within about 1e-15 of f + ε).

Every term is the reflectance an NBRDF gives, clamped as it clamps it, taken into the mapped space: the edit is
the viewer's "keeping each material" mode (:mod:`frenbrdf.render.viewer.sources`), here at any t.

Examples
--------
>>> a = model.reconstruct(values_a, (wi_a, wo_a))            # refine="full"      # doctest: +SKIP
>>> b = model.reconstruct(values_b, (wi_b, wo_b))                                # doctest: +SKIP
>>> halfway = model.edit(a, b, 0.5)                                              # doctest: +SKIP
>>> halfway(wi, wo).shape                                                        # doctest: +SKIP
(N, 3)
>>> halfway.to_merl("halfway.binary")                                            # doctest: +SKIP
>>> path = model.edit(a, b, [0, 0.25, 0.5, 0.75, 1])  # five materials; path[k] is one   # doctest: +SKIP
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..io.merl import write_merl
from .mapping import LogRelativeMapping
from .nbrdf import NBRDF, merl_bin_inputs, nbrdf_merl_table


@dataclass
class _Ends:
    """What every position of one edit shares: the two materials, their decodings, the mapping, and the
    materials' values at the MERL bins once a table has been asked for (each computed once)."""

    a: NBRDF
    b: NBRDF
    own_a: NBRDF
    own_b: NBRDF
    mapping: LogRelativeMapping
    tables: dict[str, np.ndarray] = field(default_factory=dict)

    def bin_values(self, name: str) -> np.ndarray:
        """The reflectance of ``a``, ``b``, ``own_a`` or ``own_b`` at the MERL bins above the horizon, ``(n, 3)``."""
        if name not in self.tables:
            self.tables[name] = table_values(getattr(self, name))
        return self.tables[name]


def table_values(nbrdf: NBRDF) -> np.ndarray:
    """An NBRDF's reflectance at the MERL bins above the horizon, ``(n, 3)`` in :func:`merl_bin_inputs`' order: what
    :meth:`NBRDF.merl_table` writes there (an ordered NBRDF: each pair in the table's order)."""
    above, _ = merl_bin_inputs()
    table = nbrdf.merl_table()
    return np.stack([table[channel][above] for channel in range(3)], axis=-1)


class EditedMaterial:
    """Materials along the edit between two reconstructions that keeps each (see the module docstring).

    Evaluate it like an :class:`NBRDF` (``edit(wi, wo)``), render it (:func:`frenbrdf.render.render` takes any
    callable), or write it as a MERL table (:meth:`to_merl`), which every command reads. It holds one material per
    position t (:attr:`t`); index one, ``edit[k]``, as an NBRDF of several materials is indexed.
    """

    def __init__(self, ends: _Ends, paths: list[NBRDF], t: np.ndarray):
        if len(paths) != len(t):
            raise ValueError(f"one decoding per position: {len(paths)} decodings for {len(t)} positions")
        self._ends, self.paths = ends, list(paths)
        #: The positions along the edit, ``(T,)``: 0 is material a, 1 material b.
        self.t = np.asarray(t, dtype=np.float64)

    @property
    def mapping(self) -> LogRelativeMapping:
        """The model's mapping: the space the edit adds in."""
        return self._ends.mapping

    @property
    def a(self) -> NBRDF:
        """Material a (the edit at t = 0)."""
        return self._ends.a

    @property
    def b(self) -> NBRDF:
        """Material b (the edit at t = 1)."""
        return self._ends.b

    def __len__(self) -> int:
        return len(self.t)

    def __getitem__(self, index: int) -> EditedMaterial:
        return EditedMaterial(self._ends, [self.paths[index]], self.t[[index]])

    def _only(self) -> float:
        if len(self) != 1:
            raise ValueError(f"this edit holds {len(self)} materials (t = {', '.join(f'{t:g}' for t in self.t)}); "
                             "index one first, e.g. edit[0]")
        return float(self.t[0])

    def _terms(self) -> list[tuple[str, float]]:
        """The edit's terms at its one t, as (material, weight), in the order they are summed; those of weight 0
        left out (at t = 0 and 1 one material and its decoding)."""
        t = self._only()
        terms = [("a", 1 - t), ("b", t), ("path", 1.0), ("own_a", -(1 - t)), ("own_b", -t)]
        return [(name, weight) for name, weight in terms if weight != 0]

    def _combine(self, mapped) -> np.ndarray:
        """``(1 − t) y_a + t y_b + (D(z_t) − (1 − t) D(z_a) − t D(z_b))``, ``mapped(name)`` giving each term's
        mapped values, summed in this order (the module docstring says why)."""
        terms = self._terms()
        blend = [(name, weight) for name, weight in terms if name in ("a", "b")]
        departure = [(name, weight) for name, weight in terms if name not in ("a", "b")]
        total = sum(weight * mapped(name) for name, weight in blend)
        step = sum(weight * mapped(name) for name, weight in departure)  # D(z_t) first: exact 0 at the ends
        return total + step

    def __call__(self, wi, wo) -> np.ndarray:
        """Reflectance at direction pairs, each ``(..., 3)`` → RGB ``(..., 3)``; 0 below the horizon."""
        self._only()
        wi, wo = np.asarray(wi, dtype=np.float64), np.asarray(wo, dtype=np.float64)
        reference = self.mapping.reference_at(wi, wo)
        materials = {"a": self.a, "b": self.b, "path": self.paths[0], "own_a": self._ends.own_a,
                     "own_b": self._ends.own_b}
        mapped = self._combine(lambda name: self.mapping.forward(materials[name](wi, wo), reference))
        rgb = self.mapping.inverse(mapped, reference)
        above = (wi[..., 2] > 0) & (wo[..., 2] > 0)
        return np.where(above[..., None], rgb, 0.0)

    def merl_table(self) -> np.ndarray:
        """The material at every MERL bin, ``(3, 90, 90, 180)``, missing bins marked as MERL does: each term's table
        (:meth:`NBRDF.merl_table`) combined bin by bin; the two materials' and their decodings' are computed once
        per edit."""
        self._only()
        above, _ = merl_bin_inputs()
        reference = self.mapping.reference_bins()[:, above.reshape(-1)].T
        path = table_values(self.paths[0]) if any(name == "path" for name, _ in self._terms()) else None

        def mapped(name: str) -> np.ndarray:
            values = path if name == "path" else self._ends.bin_values(name)
            return self.mapping.forward(values, reference)

        values = self.mapping.inverse(self._combine(mapped), reference)
        return nbrdf_merl_table(lambda inputs: values)

    def to_merl(self, path: str | os.PathLike) -> None:
        """Writes the material as a MERL file (atomically)."""
        write_merl(path, self.merl_table())


def interpolate(z_a, z_b, t, *, extrapolate: bool = False) -> np.ndarray:
    """Linear interpolation of latents, ``(1 − t) z_a + t z_b`` (material editing).

    ``t`` is a number or an array (a leading axis is added). Values outside [0, 1]
    extrapolate beyond the two materials, which decodes to materials nobody measured:
    they raise ``ValueError`` unless ``extrapolate=True``.
    """
    z_a, z_b = np.asarray(z_a, dtype=np.float64), np.asarray(z_b, dtype=np.float64)
    if z_a.shape != z_b.shape:
        raise ValueError(f"latents must have the same shape, got {z_a.shape} and {z_b.shape}")
    t = np.asarray(t, dtype=np.float64)
    if not np.all(np.isfinite(t)):
        raise ValueError("t must be finite")
    if not extrapolate and (t.min() < 0 or t.max() > 1):
        raise ValueError(f"t must lie in [0, 1], got {t.min()} … {t.max()}; pass extrapolate=True to go beyond")
    t = t.reshape(t.shape + (1,) * z_a.ndim)
    return (1 - t) * z_a + t * z_b


def _same_mapping(x: LogRelativeMapping, y: LogRelativeMapping) -> bool:
    return x.epsilon == y.epsilon and x.offset == y.offset and x.reference.shape == y.reference.shape \
        and np.array_equal(x.reference.astype(np.float32), y.reference.astype(np.float32))


def edit(model, a, b, t) -> EditedMaterial:
    """The edit between two reconstructions that keeps each (see the module docstring); ``Model.edit``.

    Parameters
    ----------
    model
        The :class:`frenbrdf.Model` that reconstructed both.
    a, b
        :class:`frenbrdf.models.reconstruct.Reconstruction` s of that model (anything with its latent ``.z``
        ``(latent,)`` and its material ``.nbrdf``, one NBRDF in the model's mapping).
    t
        A position in [0, 1] or a 1-D array of them: 0 is ``a``, 1 is ``b``.

    Returns
    -------
    EditedMaterial
        One material per position (index it for one of several).

    Raises
    ------
    ValueError
        t outside [0, 1] or not finite, or a reconstruction that is not of this model (its latent's size, its
        mapping).
    """
    latent = model.config.encoder.latent
    latents = []
    for name, result in (("a", a), ("b", b)):
        z = np.asarray(result.z, dtype=np.float64)
        if z.shape != (latent,):
            raise ValueError(f"reconstruction {name}'s latent has shape {z.shape}; this model's is ({latent},): "
                             "reconstruct both with the model that edits")
        if len(result.nbrdf) != 1:
            raise ValueError(f"reconstruction {name} holds {len(result.nbrdf)} materials; give one")
        if not _same_mapping(result.nbrdf.mapping, model.mapping):
            raise ValueError(f"reconstruction {name}'s NBRDF maps reflectance unlike this model (another f_ref, ε or "
                             "form): its residual would be taken in another space; reconstruct it with this model")
        latents.append(z)
    ts = np.asarray(t, dtype=np.float64)
    if ts.ndim > 1:
        raise ValueError(f"t must be a number or a 1-D array, got shape {ts.shape}")
    path_latents = interpolate(latents[0], latents[1], ts.reshape(-1))  # checks t: finite, in [0, 1]
    # Each latent decoded alone: the decoding at t = 0 is then D(z_a) bit for bit (a batch may round otherwise).
    paths = [model.decode(z) for z in path_latents]
    ends = _Ends(a.nbrdf, b.nbrdf, model.decode(latents[0]), model.decode(latents[1]), model.mapping)
    return EditedMaterial(ends, paths, ts.reshape(-1))
