"""Training data: MERL folders, splits and sample sets.

Every model in the package works in the *mapped* space (:mod:`frenbrdf.models.mapping`),

    y = ln((f + ε) / (f_ref + ε)),     f = (f_ref + ε) · exp(y) − ε  (clamped to ≥ 0),

where f_ref is the median BRDF of the training materials, per bin (the default) or per
channel. The mapping is stored with every trained model so that decoding is exact.

A material is sampled at MERL bins, never at missing ones. One sample is the 9-vector
the set encoder reads, ``[y_r, y_g, y_b, H_x, H_y, H_z, D_x, D_y, D_z]``, with the
cosine of the incident angle used to weight the reconstruction loss (paper Eq. 1).

Examples
--------
>>> from frenbrdf.data.folders import list_materials, split_materials
>>> files = list_materials("bank/")                                  # doctest: +SKIP
>>> split = split_materials([f.stem for f in files], seed=0)         # doctest: +SKIP
"""

from __future__ import annotations

import fnmatch
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from ..io.formats import MEASURED, read_table
from ..io.merl import N_BINS
from ..models.mapping import LogRelativeMapping, MappingConfig, channel_median
from ..models.nbrdf import bin_geometry

# --------------------------------------------------------------------------- files, split


def list_materials(folder: str | os.PathLike) -> list[Path]:
    """The measured materials of a folder, sorted by name: MERL files (``*.binary``) and RGL
    measurements (``*.bsdf``), which may be mixed (:func:`frenbrdf.io.read_table` reads either).

    Raises
    ------
    FileNotFoundError, NotADirectoryError, PermissionError
        The folder does not exist, is a file, or cannot be listed.
    ValueError
        The folder holds no material file, or two files of one name (``a.binary`` and ``a.bsdf``).
    """
    folder = Path(folder)
    if not folder.exists():
        raise FileNotFoundError(f"data folder {folder} does not exist")
    if not folder.is_dir():
        raise NotADirectoryError(f"data folder {folder} is not a folder")
    try:  # listed here, not by glob, which reads a folder it may not list as an empty one
        names = sorted(entry.name for entry in os.scandir(folder))
    except PermissionError as error:
        raise PermissionError(f"data folder {folder} cannot be listed: {error.strerror}") from None
    files = [folder / name for name in names if name.endswith(MEASURED)]
    if not files:
        raise ValueError(f"data folder {folder} holds no material files (*.binary or *.bsdf); "
                         "create some with `frenbrdf synth` or `frenbrdf import-nbrdf`")
    stems = [path.stem for path in files]
    if twice := sorted({stem for stem in stems if stems.count(stem) > 1}):
        raise ValueError(f"data folder {folder} holds two files of each of the materials {twice}; keep one of each")
    return files


@dataclass(frozen=True)
class Split:
    """Material names of the training, validation and test sets."""

    train: tuple[str, ...]
    val: tuple[str, ...]
    test: tuple[str, ...]
    seed: int

    def to_json(self) -> dict:
        """The split as JSON data (tuples as lists), as :meth:`from_json` reads it."""
        return {key: list(value) if isinstance(value, tuple) else value for key, value in asdict(self).items()}

    @classmethod
    def from_json(cls, data: dict, where: str = "split") -> Split:
        """The inverse of :meth:`to_json`, checked: three lists of material names and an integer seed (``where``
        names the source in messages)."""
        if not isinstance(data, dict):
            raise ValueError(f"{where} must be a JSON object, got {type(data).__name__}")
        parts = {}
        for key in ("train", "val", "test"):
            names = data.get(key)
            if not isinstance(names, (list, tuple)) or not all(isinstance(name, str) for name in names):
                raise ValueError(f"{where}: {key} must be a list of material names, got {names!r:.80}")
            parts[key] = tuple(names)
        seed = data.get("seed")
        if isinstance(seed, bool) or not isinstance(seed, int):
            raise ValueError(f"{where}: seed must be an integer, got {seed!r:.80}")
        return cls(**parts, seed=seed)


def split_materials(names, seed: int, fractions: tuple[float, float, float] = (0.7, 0.1, 0.2),
                    holdout=()) -> Split:
    """A random split of materials by name (70/10/20 by default), reproducible from the seed.

    Every part gets at least one material, so at least three are needed. With ``holdout``
    (glob patterns over names, e.g. ``"*fabric*"``) the matching materials are the test set
    (a held-out family) and the others are split into train/validation by the first two
    fractions, renormalised.
    """
    names = sorted(names)
    if len(set(names)) != len(names):
        raise ValueError("material names must be unique")
    if holdout:
        return _held_out_split(names, seed, fractions, tuple(holdout))
    if len(names) < 3:
        raise ValueError(f"a train/validation/test split needs at least 3 materials, got {len(names)}")
    if len(fractions) != 3 or min(fractions) < 0 or not np.isclose(sum(fractions), 1.0):
        raise ValueError(f"split fractions must be three non-negative numbers summing to 1, got {fractions}")
    order = np.random.default_rng(seed).permutation(len(names))
    n_val = max(1, round(fractions[1] * len(names)))
    n_test = max(1, round(fractions[2] * len(names)))
    n_train = len(names) - n_val - n_test
    if n_train < 1:
        raise ValueError(f"{len(names)} materials leave none for training with fractions {fractions}")
    pick = [names[i] for i in order]
    return Split(tuple(sorted(pick[:n_train])), tuple(sorted(pick[n_train:n_train + n_val])),
                 tuple(sorted(pick[n_train + n_val:])), seed)


def _held_out_split(names: list[str], seed: int, fractions, patterns: tuple[str, ...]) -> Split:
    test = [name for name in names if any(fnmatch.fnmatchcase(name, pattern) for pattern in patterns)]
    rest = [name for name in names if name not in set(test)]
    if not test:
        raise ValueError(f"holdout {list(patterns)} matches none of the {len(names)} materials")
    if len(rest) < 2:
        raise ValueError(f"holdout {list(patterns)} matches {len(test)} of the {len(names)} materials, leaving "
                         f"{len(rest)} for training and validation (at least 2 are needed)")
    if len(fractions) != 3 or min(fractions) < 0 or fractions[0] + fractions[1] <= 0:
        raise ValueError(f"split fractions must be three non-negative numbers, the first two not both 0, got "
                         f"{fractions}")
    order = np.random.default_rng(seed).permutation(len(rest))
    n_val = min(len(rest) - 1, max(1, round(fractions[1] / (fractions[0] + fractions[1]) * len(rest))))
    pick = [rest[i] for i in order]
    return Split(tuple(sorted(pick[n_val:])), tuple(sorted(pick[:n_val])), tuple(test), seed)


# --------------------------------------------------------------------------- samples


@dataclass
class SampleBatch:
    """Samples of B materials, N each."""

    coords: torch.Tensor
    """(B, N, 6): the NBRDF input (H, D)."""
    values: torch.Tensor
    """(B, N, 3): mapped values."""
    cos_in: torch.Tensor
    """(B, N): cos θ_i."""

    def encoder_input(self) -> torch.Tensor:
        """(B, N, 9): what the set encoder reads."""
        return torch.cat([self.values, self.coords], dim=-1)

    def to(self, device) -> SampleBatch:
        return SampleBatch(self.coords.to(device), self.values.to(device), self.cos_in.to(device))

    def take(self, materials: slice) -> SampleBatch:
        """The samples of some of the materials (a slice of the batch)."""
        return SampleBatch(self.coords[materials], self.values[materials], self.cos_in[materials])


class MaterialBank:
    """Mapped tables of several materials, held in memory, ready to sample.

    Parameters
    ----------
    names
        One name per material.
    mapped
        ``(M, N_BINS, 3)`` float32 mapped values (anything at missing bins).
    valid
        ``(M, N_BINS)`` bool: bins that hold a measurement.
    """

    def __init__(self, names, mapped: torch.Tensor, valid: torch.Tensor):
        self.names = list(names)
        self.mapped, self.valid = mapped, valid
        self.index = {name: i for i, name in enumerate(self.names)}
        # Indices of the valid bins, once per distinct mask (usually one for all materials).
        self._valid_bins: list[torch.Tensor] = [torch.nonzero(v).squeeze(1) for v in valid]
        if any(len(bins) == 0 for bins in self._valid_bins):
            empty = [n for n, bins in zip(self.names, self._valid_bins, strict=True) if len(bins) == 0]
            raise ValueError(f"materials without a single valid bin: {empty}")

    def __len__(self) -> int:
        return len(self.names)

    def valid_bins(self, material: int) -> torch.Tensor:
        """Flat indices of a material's valid bins."""
        return self._valid_bins[material]

    def sample(self, materials, n: int, generator: torch.Generator) -> SampleBatch:
        """``n`` random valid bins (with replacement) of each listed material index."""
        if n < 1:
            raise ValueError(f"the number of samples must be ≥ 1, got {n}")
        bins = torch.stack([self._valid_bins[m][torch.randint(len(self._valid_bins[m]), (n,), generator=generator)]
                            for m in materials])
        return self.at_bins(materials, bins)

    def at_bins(self, materials, bins: torch.Tensor) -> SampleBatch:
        """The samples of each listed material index at its row of flat bin indices ``bins`` ``(B, n)``."""
        geometry = bin_geometry()
        rows = torch.as_tensor(list(materials))[:, None]
        return SampleBatch(geometry.half_diff[bins], self.mapped[rows, bins], geometry.cos_in[bins])


def read_valid_table(path) -> np.ndarray:
    """One MERL file (or measurement) → ``(3, N_BINS)`` float64 reflectance with missing bins as NaN."""
    table = read_table(path).reshape(3, N_BINS)
    table[:, np.any(table < 0, axis=0)] = np.nan
    return table


def read_tables(files, progress: bool = True) -> np.ndarray:
    """MERL files → ``(M, 3, N_BINS)`` float64 reflectance with missing bins as NaN (~35 MB a material)."""
    tables = np.empty((len(files), 3, N_BINS), dtype=np.float64)
    for i, path in enumerate(tqdm(files, desc="reading materials", disable=not progress, leave=False)):
        tables[i] = read_valid_table(path)
    return tables


def files_mapping(files, config: MappingConfig, progress: bool = True) -> LogRelativeMapping:
    """:meth:`LogRelativeMapping.from_tables` of MERL files, the same numbers. With a reference per channel
    (the default) it holds one channel of all the tables at a time, a third of them (each file is read three
    times); per bin, all of them."""
    if config.reference != "per_channel":
        return LogRelativeMapping.from_tables(read_tables(files, progress), config)
    values = np.empty((len(files), N_BINS), dtype=np.float64)
    medians = []
    for channel in tqdm(range(3), desc="reference f_ref", disable=not progress, leave=False):
        for i, path in enumerate(files):
            values[i] = read_valid_table(path)[channel]
        medians.append(channel_median(values))
    return LogRelativeMapping.from_reference(np.array(medians), config)


def mapped_bank(names, tables, mapping: LogRelativeMapping) -> MaterialBank:
    """Maps reflectance tables into a :class:`MaterialBank`: one ``(3, N_BINS)`` table per name (missing = NaN),
    as an ``(M, 3, N_BINS)`` array or any iterable of them (e.g. read one at a time, so that only the mapped
    float32 bank is ever whole in memory)."""
    reference = mapping.reference_bins()
    valid = np.empty((len(names), N_BINS), dtype=bool)
    mapped = np.empty((len(names), N_BINS, 3), dtype=np.float32)
    count = 0
    for count, table in enumerate(tables, start=1):
        if count > len(names):
            raise ValueError(f"more tables than the {len(names)} names")
        valid[count - 1] = ~np.any(np.isnan(table), axis=0)
        with np.errstate(invalid="ignore"):
            mapped[count - 1] = np.nan_to_num(mapping.forward(table, reference)).T
    if count != len(names):
        raise ValueError(f"{count} tables for {len(names)} names")
    return MaterialBank(names, torch.from_numpy(mapped), torch.from_numpy(valid))


#: Incident angles (degrees) at which :func:`max_directional_albedo` integrates (Fresnel makes
#: glossy materials brightest near grazing, so the last is close to it).
ALBEDO_INCIDENT_DEGREES = (0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0)


def max_directional_albedo(bank: MaterialBank, mapping: LogRelativeMapping, materials=None, *,
                           nodes: int = 96) -> torch.Tensor:
    """Each material's largest directional albedo per channel, ``(M, 3)`` float32.

    A(θ_i) = ∫ f(ω_i, ω_o) cos θ_o dω_o over the outgoing hemisphere, at the incident angles
    :data:`ALBEDO_INCIDENT_DEGREES`, by a fixed product rule: Gauss–Legendre in cos θ_o
    (``nodes`` points) times ``2 · nodes`` midpoints in φ_o. f is read from the bank (un-mapped)
    in the MERL bin holding each direction pair (:func:`frenbrdf.io.merl.merl_angles_to_bin`, as
    ``merl_lookup_directions(method="nearest")`` does); missing bins count as 0. Measured
    against a fine quadrature of analytic materials (tests/test_augment.py): within 5 % at
    these angles, and at most ~3 % below the largest albedo at any incidence.
    """
    from ..io.merl import merl_angles_to_bin
    from ..numerics.coords import directions_to_rusinkiewicz

    x, w = np.polynomial.legendre.leggauss(nodes)
    cos_o, weight = (x + 1) / 2, w / 2
    phi = (np.arange(2 * nodes) + 0.5) * np.pi / nodes
    sin_o = np.sqrt(1 - cos_o ** 2)
    wo = np.stack([np.outer(sin_o, np.cos(phi)), np.outer(sin_o, np.sin(phi)),
                   np.repeat(cos_o[:, None], len(phi), axis=1)], axis=-1).reshape(-1, 3)
    # ∫ f cos θ_o dω_o = ∫₀¹ ∫₀^2π f μ_o dφ dμ_o.
    quadrature = torch.from_numpy(np.repeat(weight * cos_o, len(phi)) * (np.pi / nodes)).float()
    theta_i = np.radians(ALBEDO_INCIDENT_DEGREES)
    wi = np.stack([np.sin(theta_i), np.zeros_like(theta_i), np.cos(theta_i)], axis=-1)
    angles = directions_to_rusinkiewicz(np.repeat(wi, len(wo), axis=0), np.tile(wo, (len(wi), 1)))
    index = merl_angles_to_bin(angles[:, [0, 2, 3]])
    bins = torch.from_numpy(np.ravel_multi_index(tuple(index.T), (90, 90, 180)))
    reference = torch.from_numpy(np.ascontiguousarray(mapping.reference_bins()[:, bins.numpy()].T)).float()
    albedos = []
    for m in range(len(bank)) if materials is None else materials:
        f = mapping.inverse(bank.mapped[m, bins], reference) * bank.valid[m, bins, None]
        albedos.append((f.reshape(len(wi), len(wo), 3) * quadrature[:, None]).sum(1).amax(0))
    return torch.stack(albedos)
