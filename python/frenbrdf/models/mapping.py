"""The log-relative mapping of reflectance, in which every model of the package works:

    y = ln(c + (f + ε) / (f_ref + ε)),     f = (f_ref + ε) · (exp(y) − c) − ε  (clamped to 0 … MAX_REFLECTANCE),

with c = 0 (``form="ratio"``, ours) or c = 1 (``form="one_plus_ratio"``, HyperBRDF's),

where f_ref is the median BRDF of the training materials, per bin (the default) or per
channel. The mapping is stored with every trained model so that decoding is exact.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ..io.merl import N_BINS, SHAPE, merl_lookup_directions
from ..io.reflectance import MAX_REFLECTANCE

#: The constant c added to the ratio inside the logarithm, per form.
FORM_OFFSETS = {"ratio": 0.0, "one_plus_ratio": 1.0}


@dataclass
class MappingConfig:
    """The log-relative mapping of reflectance (docs/method.md §3)."""

    epsilon: float = 0.002
    """Offset that keeps the logarithm finite at zero reflectance."""
    reference: str = "per_channel"
    """``"per_channel"``: one median per channel (3 numbers); ``"per_bin"``: the per-bin median of the
    training tables (17.5 MB; HyperBRDF's). Within noise of each other over three seeds, in and out of
    distribution, with the decoder initialised at scale 1 (research/colour.md); per channel the mapping is
    three numbers and needs no interpolation of f_ref between bins."""
    form: str = "ratio"
    """``"ratio"``: y = ln(ratio) (NBRDF, ours); ``"one_plus_ratio"``: y = ln(1 + ratio) (HyperBRDF's
    data_processing), with ratio = (f + ε) / (f_ref + ε)."""

    def __post_init__(self):
        if self.form not in FORM_OFFSETS:
            raise ValueError(f"mapping.form must be one of {tuple(FORM_OFFSETS)}, got {self.form!r}")
        if not (self.epsilon > 0 and np.isfinite(self.epsilon)):
            raise ValueError(f"mapping.epsilon must be a positive number, got {self.epsilon}")
        if self.reference not in ("per_bin", "per_channel"):
            raise ValueError(f"mapping.reference must be 'per_bin' or 'per_channel', got {self.reference!r}")


#: Bins per chunk of :meth:`LogRelativeMapping.from_tables`' median.
_MEDIAN_CHUNK = 1 << 16


def channel_median(values: np.ndarray) -> float:
    """The median of one channel's values over all tables and bins (missing = NaN; 0 where all are missing)."""
    return float(np.nan_to_num(np.nanmedian(values)))


def _median_of_present(tables: np.ndarray) -> np.ndarray:
    """The median over materials of ``tables`` ``(M, 3, B)`` (missing = NaN): bins missing in no material take
    the plain median, bins missing in some the median of the others (slower), bins missing in all 0."""
    missing = np.isnan(tables)
    some, every = missing.any(axis=0), missing.all(axis=0)
    reference = np.zeros(tables.shape[1:], dtype=np.float64)
    complete = ~some
    reference[complete] = np.median(tables[:, complete], axis=0)
    partial = some & ~every
    if partial.any():
        reference[partial] = np.nanmedian(tables[:, partial], axis=0)
    return reference


class LogRelativeMapping:
    """Reflectance ↔ mapped values, relative to a reference BRDF.

    Parameters
    ----------
    reference
        f_ref: a MERL-shaped table ``(3, 90, 90, 180)`` or one value per channel ``(3,)``;
        finite and ≥ 0.
    epsilon
        The offset ε.
    offset
        The constant c added to the ratio (0 or 1, :data:`FORM_OFFSETS`).
    """

    def __init__(self, reference, epsilon: float = 0.002, offset: float = 0.0):
        reference = np.asarray(reference, dtype=np.float64)
        if reference.shape not in ((3,), SHAPE):
            raise ValueError(f"the reference BRDF must have shape (3,) or {SHAPE}, got {reference.shape}")
        if not np.all(np.isfinite(reference)) or reference.min() < 0:
            raise ValueError("the reference BRDF must be finite and non-negative")
        if offset not in FORM_OFFSETS.values():
            raise ValueError(f"the mapping's offset must be one of {sorted(FORM_OFFSETS.values())}, got {offset}")
        if not (isinstance(epsilon, (int, float, np.floating, np.integer)) and 0 < epsilon < np.inf):
            raise ValueError(f"the mapping's ε must be a positive number, got {epsilon!r} (with ε ≤ 0 the logarithm "
                             "of a zero reflectance is not finite, and the material decodes to another)")
        self.reference = reference
        self.epsilon = float(epsilon)
        self.offset = float(offset)

    @classmethod
    def from_tables(cls, tables: np.ndarray, config: MappingConfig) -> LogRelativeMapping:
        """The median of ``tables`` ``(M, 3, N_BINS)`` (missing = NaN) as reference."""
        if config.reference == "per_channel":
            # One channel at a time (a median copies what it reads: all three at once would copy the bank twice).
            reference = np.array([channel_median(tables[:, channel]) for channel in range(tables.shape[1])])
        else:
            reference = np.zeros(tables.shape[1:], dtype=np.float64)
            # A chunk of bins at a time: a median copies what it reads, and all bins at once would
            # copy the whole bank (~35 MB per material in float64) once more, twice.
            for start in range(0, tables.shape[-1], _MEDIAN_CHUNK):
                part = tables[..., start:start + _MEDIAN_CHUNK]
                reference[..., start:start + _MEDIAN_CHUNK] = _median_of_present(part)
            reference = reference.reshape(SHAPE)
        return cls.from_reference(reference, config)

    @classmethod
    def from_reference(cls, reference: np.ndarray, config: MappingConfig) -> LogRelativeMapping:
        """The mapping with this reference (a median of tables; negative values raised to 0) and ``config``'s ε and form."""
        return cls(np.maximum(reference, 0.0), config.epsilon, FORM_OFFSETS[config.form])

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
        torch_in = isinstance(reflectance, torch.Tensor)
        ratio = (reflectance + self.epsilon) / (reference + self.epsilon)
        if self.offset:  # ln(1 + ratio), exact for a tiny ratio
            return torch.log1p(ratio) if torch_in else np.log1p(ratio)
        return torch.log(ratio) if torch_in else np.log(ratio)

    def inverse(self, mapped, reference):
        """Mapped values → reflectance, clamped to 0 … :data:`~frenbrdf.io.reflectance.MAX_REFLECTANCE` (numpy or
        torch): the largest value any reader accepts is the largest a model gives back, whatever it extrapolates."""
        if isinstance(mapped, torch.Tensor):
            grown = torch.expm1(mapped) if self.offset else torch.exp(mapped)  # exp(y) − c
            return ((reference + self.epsilon) * grown - self.epsilon).clamp(0.0, MAX_REFLECTANCE)
        with np.errstate(over="ignore"):
            grown = np.expm1(mapped) if self.offset else np.exp(mapped)
            linear = (reference + self.epsilon) * grown - self.epsilon
        return np.clip(linear, 0.0, MAX_REFLECTANCE)

    def state(self) -> dict:
        """What the mapping is: f_ref (float32), ε and the offset c."""
        return {"reference": self.reference.astype(np.float32), "epsilon": self.epsilon, "offset": self.offset}

    @classmethod
    def from_state(cls, state: dict) -> LogRelativeMapping:
        """The inverse of :meth:`state`; states saved before the offset existed have c = 0."""
        return cls(np.asarray(state["reference"], dtype=np.float64), state["epsilon"], state.get("offset", 0.0))
