"""Training data: MERL folders, the log-relative mapping, splits and sample sets.

Every model in the package works in the *mapped* space of DESIGN §6,

    y = ln((f + ε) / (f_ref + ε)),     f = (f_ref + ε) · exp(y) − ε  (clamped to ≥ 0),

where f_ref is the median BRDF of the training materials, per bin (the default) or per
channel. The mapping is stored with every trained model so that decoding is exact.

A material is sampled at MERL bins, never at missing ones. One sample is the 9-vector
the set encoder reads, ``[y_r, y_g, y_b, H_x, H_y, H_z, D_x, D_y, D_z]``, with the
cosine of the incident angle used to weight the reconstruction loss (paper Eq. 1).

Examples
--------
>>> from frenbrdf.data import list_materials, split_materials
>>> files = list_materials("bank/")                                  # doctest: +SKIP
>>> split = split_materials([f.stem for f in files], seed=0)         # doctest: +SKIP
"""

from __future__ import annotations

import functools
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from tqdm.auto import tqdm

from .coords import half_diff_vectors
from .merl import SHAPE, merl_bin_directions, merl_lookup_directions, read_merl

#: Number of bins per channel of a MERL table.
N_BINS = SHAPE[1] * SHAPE[2] * SHAPE[3]


# --------------------------------------------------------------------------- files, split


def list_materials(folder: str | os.PathLike) -> list[Path]:
    """The MERL files (``*.binary``) of a folder, sorted by name.

    Raises
    ------
    FileNotFoundError, NotADirectoryError
        The folder does not exist or is a file.
    ValueError
        The folder holds no ``.binary`` file.
    """
    folder = Path(folder)
    if not folder.exists():
        raise FileNotFoundError(f"data folder {folder} does not exist")
    if not folder.is_dir():
        raise NotADirectoryError(f"data folder {folder} is not a folder")
    files = sorted(folder.glob("*.binary"))
    if not files:
        raise ValueError(f"data folder {folder} holds no MERL files (*.binary); "
                         "create some with `frenbrdf synth` or `frenbrdf import-nbrdf`")
    return files


@dataclass(frozen=True)
class Split:
    """Material names of the training, validation and test sets."""

    train: tuple[str, ...]
    val: tuple[str, ...]
    test: tuple[str, ...]
    seed: int

    def to_json(self) -> dict:
        return {key: list(value) if isinstance(value, tuple) else value for key, value in asdict(self).items()}

    @classmethod
    def from_json(cls, data: dict) -> Split:
        return cls(tuple(data["train"]), tuple(data["val"]), tuple(data["test"]), int(data["seed"]))


def split_materials(names, seed: int, fractions: tuple[float, float, float] = (0.7, 0.1, 0.2)) -> Split:
    """A random split of materials by name (70/10/20 by default), reproducible from the seed.

    Every part gets at least one material, so at least three are needed.
    """
    names = sorted(names)
    if len(set(names)) != len(names):
        raise ValueError("material names must be unique")
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


# --------------------------------------------------------------------------- mapping


@dataclass
class MappingConfig:
    """The log-relative mapping of reflectance (DESIGN §6)."""

    epsilon: float = 0.002
    """Offset that keeps the logarithm finite at zero reflectance."""
    reference: str = "per_bin"
    """``"per_bin"``: f_ref is the per-bin median of the training tables; ``"per_channel"``: one median per channel."""

    def __post_init__(self):
        if not (self.epsilon > 0 and np.isfinite(self.epsilon)):
            raise ValueError(f"mapping.epsilon must be a positive number, got {self.epsilon}")
        if self.reference not in ("per_bin", "per_channel"):
            raise ValueError(f"mapping.reference must be 'per_bin' or 'per_channel', got {self.reference!r}")


class LogRelativeMapping:
    """Reflectance ↔ mapped values, relative to a reference BRDF.

    Parameters
    ----------
    reference
        f_ref: a MERL-shaped table ``(3, 90, 90, 180)`` or one value per channel ``(3,)``;
        finite and ≥ 0.
    epsilon
        The offset ε.
    """

    def __init__(self, reference, epsilon: float = 0.002):
        reference = np.asarray(reference, dtype=np.float64)
        if reference.shape not in ((3,), SHAPE):
            raise ValueError(f"the reference BRDF must have shape (3,) or {SHAPE}, got {reference.shape}")
        if not np.all(np.isfinite(reference)) or reference.min() < 0:
            raise ValueError("the reference BRDF must be finite and non-negative")
        self.reference = reference
        self.epsilon = float(epsilon)

    @classmethod
    def from_tables(cls, tables: np.ndarray, config: MappingConfig) -> LogRelativeMapping:
        """The median of ``tables`` ``(M, 3, N_BINS)`` (missing = NaN) as reference."""
        if config.reference == "per_channel":
            reference = np.nan_to_num(np.nanmedian(tables.transpose(1, 0, 2).reshape(3, -1), axis=1))
        else:
            # Bins missing in no material take the plain median, bins missing in some the
            # median of the others (slower), bins missing in all get f_ref = 0.
            missing = np.isnan(tables)
            some, every = missing.any(axis=0), missing.all(axis=0)
            reference = np.zeros(tables.shape[1:], dtype=np.float64)
            complete = ~some
            reference[complete] = np.median(tables[:, complete], axis=0)
            partial = some & ~every
            if partial.any():
                reference[partial] = np.nanmedian(tables[:, partial], axis=0)
            reference = reference.reshape(SHAPE)
        return cls(np.maximum(reference, 0.0), config.epsilon)

    @property
    def per_bin(self) -> bool:
        return self.reference.ndim == 4

    def reference_bins(self) -> np.ndarray:
        """f_ref at every bin, ``(3, N_BINS)``."""
        return np.broadcast_to(self.reference.reshape(3, -1), (3, N_BINS))

    def reference_at(self, wi, wo) -> np.ndarray:
        """f_ref at direction pairs ``(..., 3)`` (trilinear in the MERL bins)."""
        if not self.per_bin:
            return np.broadcast_to(self.reference, np.shape(wi)[:-1] + (3,))
        return np.maximum(merl_lookup_directions(self.reference, wi, wo, method="trilinear"), 0.0)

    def forward(self, reflectance, reference):
        """Reflectance → mapped values (numpy or torch, broadcasting)."""
        log = torch.log if isinstance(reflectance, torch.Tensor) else np.log
        return log((reflectance + self.epsilon) / (reference + self.epsilon))

    def inverse(self, mapped, reference):
        """Mapped values → reflectance, clamped to ≥ 0 (numpy or torch)."""
        if isinstance(mapped, torch.Tensor):
            return ((reference + self.epsilon) * torch.exp(mapped) - self.epsilon).clamp_min(0.0)
        return np.maximum((reference + self.epsilon) * np.exp(mapped) - self.epsilon, 0.0)

    def state(self) -> dict:
        return {"reference": self.reference.astype(np.float32), "epsilon": self.epsilon}

    @classmethod
    def from_state(cls, state: dict) -> LogRelativeMapping:
        return cls(np.asarray(state["reference"], dtype=np.float64), state["epsilon"])


# --------------------------------------------------------------------------- bins and samples


@dataclass(frozen=True)
class BinGeometry:
    """What every MERL bin means to an NBRDF (φ_h = 0), shared by all materials."""

    half_diff: torch.Tensor
    """(N_BINS, 6) float32: the NBRDF input (H, D)."""
    cos_in: torch.Tensor
    """(N_BINS,) float32: cos θ_i clamped to [0, 1], the reconstruction-loss weight."""


@functools.cache
def bin_geometry() -> BinGeometry:
    wi, wo = (d.reshape(-1, 3) for d in merl_bin_directions())
    h, d = half_diff_vectors(wi, wo)
    return BinGeometry(torch.from_numpy(np.concatenate([h, d], axis=-1).astype(np.float32)),
                       torch.from_numpy(np.clip(wi[:, 2], 0.0, 1.0).astype(np.float32)))


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
            empty = [n for n, bins in zip(self.names, self._valid_bins) if len(bins) == 0]
            raise ValueError(f"materials without a single valid bin: {empty}")

    def __len__(self) -> int:
        return len(self.names)

    def sample(self, materials, n: int, generator: torch.Generator) -> SampleBatch:
        """``n`` random valid bins (with replacement) of each listed material index."""
        if n < 1:
            raise ValueError(f"the number of samples must be ≥ 1, got {n}")
        geometry = bin_geometry()
        bins = torch.stack([self._valid_bins[m][torch.randint(len(self._valid_bins[m]), (n,), generator=generator)]
                            for m in materials])
        rows = torch.as_tensor(list(materials))[:, None]
        return SampleBatch(geometry.half_diff[bins], self.mapped[rows, bins], geometry.cos_in[bins])


def read_tables(files, progress: bool = True) -> np.ndarray:
    """MERL files → ``(M, 3, N_BINS)`` float64 reflectance with missing bins as NaN."""
    tables = np.empty((len(files), 3, N_BINS), dtype=np.float64)
    for i, path in enumerate(tqdm(files, desc="reading materials", disable=not progress, leave=False)):
        table = read_merl(path).reshape(3, N_BINS)
        missing = np.any(table < 0, axis=0)
        table[:, missing] = np.nan
        tables[i] = table
    return tables


def mapped_bank(names, tables: np.ndarray, mapping: LogRelativeMapping) -> MaterialBank:
    """Maps reflectance tables ``(M, 3, N_BINS)`` (missing = NaN) into a :class:`MaterialBank`."""
    reference = mapping.reference_bins()
    valid = ~np.any(np.isnan(tables), axis=1)
    mapped = np.empty((len(tables), N_BINS, 3), dtype=np.float32)
    for i, table in enumerate(tables):
        with np.errstate(invalid="ignore"):
            mapped[i] = np.nan_to_num(mapping.forward(table, reference)).T
    return MaterialBank(names, torch.from_numpy(mapped), torch.from_numpy(valid))
