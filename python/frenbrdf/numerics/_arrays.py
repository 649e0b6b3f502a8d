"""Helpers that bring array arguments into the form the native core reads."""

from __future__ import annotations

import numpy as np


def rows(name: str, array, width: int) -> tuple[np.ndarray, tuple[int, ...]]:
    """Returns `array` as C-contiguous float64 rows `(n, width)` and its leading shape.

    Raises ValueError naming `name` when the last axis is not `width` long.
    """
    array = np.asarray(array)
    if array.ndim == 0 or array.shape[-1] != width:
        raise ValueError(f"{name} must have shape (..., {width}), got {array.shape}")
    if not (np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)):
        raise ValueError(f"{name} must hold real numbers, got dtype {array.dtype}")
    leading = array.shape[:-1]
    return np.ascontiguousarray(array.reshape(-1, width), dtype=np.float64), leading
