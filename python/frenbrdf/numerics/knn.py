"""k-nearest-neighbour Gaussian interpolation on the unit sphere (FreNBRDF Eq. 5–7).

Every target point takes the weighted mean of the values at its ``k`` nearest source
points by chordal distance d, with weights ``w ∝ exp(−d² / 2σ²)`` normalised to sum
to 1. The search runs on kiddo's immutable k-d tree in the native core.

The weights depend only on the positions. The MERL sample positions are the same for
every material, so build a :class:`KnnInterpolator` once and apply it to each material.

Examples
--------
>>> import numpy as np, frenbrdf
>>> rng = np.random.default_rng(0)
>>> src = rng.normal(size=(1000, 3)); src /= np.linalg.norm(src, axis=1, keepdims=True)
>>> dst = rng.normal(size=(10, 3)); dst /= np.linalg.norm(dst, axis=1, keepdims=True)
>>> op = frenbrdf.KnnInterpolator(src, dst, k=4, sigma=0.05)
>>> op.apply(src[:, 2]).shape       # interpolate the z coordinate
(10,)
"""

from __future__ import annotations

import numpy as np

from .. import _native
from ._arrays import rows


class KnnInterpolator:
    """Neighbours and weights from ``src`` to ``dst``, computed once, applied many times.

    Parameters
    ----------
    src
        Source points, unit vectors ``(N, 3)``. Duplicates are allowed.
    dst
        Target points, unit vectors ``(M, 3)``.
    k
        Neighbours per target, ``1 ≤ k ≤ N``.
    sigma
        Gaussian width in chordal distance, finite and > 0. Weights are computed
        relative to the nearest neighbour, so however small σ is, a target gets the
        value of its nearest source (the mean of equally near ones), never NaN.

    Raises
    ------
    ValueError
        Bad k or σ, vectors that are not finite unit vectors (norm within 1e-6 of 1),
        or arrays of the wrong shape.
    """

    def __init__(self, src, dst, k: int, sigma: float):
        src_rows, _ = rows("src", src, 3)
        dst_rows, _ = rows("dst", dst, 3)
        if src_rows.shape[0] == 0 or np.ndim(src) != 2:
            raise ValueError(f"src must be a non-empty (N, 3) array, got shape {np.shape(src)}")
        if np.ndim(dst) != 2:
            raise ValueError(f"dst must be an (M, 3) array, got shape {np.shape(dst)}")
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
            raise ValueError(f"k must be an integer, got {k!r}")
        if k < 1:
            raise ValueError(f"k = {k} must be between 1 and the number of sources ({src_rows.shape[0]})")
        self._native = _native.KnnInterpolator(src_rows, dst_rows, int(k), float(sigma))

    @property
    def k(self) -> int:
        return self._native.k

    @property
    def n_src(self) -> int:
        return self._native.n_src

    @property
    def n_dst(self) -> int:
        return self._native.n_dst

    @property
    def indices(self) -> np.ndarray:
        """Source index of each neighbour, int64 ``(M, k)``, nearest first."""
        return self._native.indices

    @property
    def weights(self) -> np.ndarray:
        """Normalised weight of each neighbour, ``(M, k)``; rows sum to 1."""
        return self._native.weights

    def apply(self, values) -> np.ndarray:
        """Interpolates ``values`` ``(N,)`` or ``(N, C)`` to ``(M,)`` or ``(M, C)``.

        Raises ValueError if the first axis is not N long or a value is NaN/inf.
        """
        values = np.asarray(values)
        if values.ndim not in (1, 2) or values.shape[0] != self.n_src:
            raise ValueError(f"values must have shape ({self.n_src},) or ({self.n_src}, C), got {values.shape}")
        as_columns = values.reshape(self.n_src, -1)
        out = self._native.apply(np.ascontiguousarray(as_columns, dtype=np.float64))
        return out[:, 0] if values.ndim == 1 else out

    def __repr__(self) -> str:
        return f"KnnInterpolator(n_src={self.n_src}, n_dst={self.n_dst}, k={self.k})"


def knn_interpolate(src, values, dst, k: int, sigma: float) -> np.ndarray:
    """One-shot kNN Gaussian interpolation: ``KnnInterpolator(src, dst, k, sigma).apply(values)``."""
    return KnnInterpolator(src, dst, k, sigma).apply(values)
