"""Spherical harmonic transforms: analysis, synthesis and the adjoint of analysis.

The transform runs in the native core (Rust, all cores, GIL released); see
:class:`SHT`. For autograd, :mod:`frenbrdf.numerics.sht_torch` wraps it in a
``torch.autograd.Function``.

Basis and normalisation
-----------------------
Real orthonormal spherical harmonics, *without* the Condon–Shortley phase:

- ``Y_l0 = λ_l0(θ)``,
- for ``m > 0`` a cosine part ``√2 λ_lm(θ) cos(mφ)`` and a sine part ``√2 λ_lm(θ) sin(mφ)``,

where ``λ_lm(θ) = √((2l+1)/4π · (l−m)!/(l+m)!) P_l^m(cos θ)`` and ``P_l^m ≥ 0`` near the
north pole. Each basis function has unit L² norm on the sphere, so a map's coefficients
have the same sum of squares as the map's integral of its square (Parseval).

Coefficient layout
------------------
``(lmax + 1)²`` coefficients in blocks by order m: first m = 0 (l = 0 … lmax), then
for each m = 1 … lmax its cosine block (l = m … lmax) followed by its sine block (same
l). :meth:`SHT.degrees_orders` gives (l, m) of every position, sine parts labelled −m.
:meth:`SHT.to_complex` / :meth:`SHT.from_complex` convert to and from the complex
``m ≥ 0`` layout of ducc0 and torch-harmonics (orthonormal, Condon–Shortley phase,
``f = Σ_l a_l0 Y_l0 + 2 Re Σ_{m>0} a_lm Y_lm``).

Grids
-----
``nlat`` rings of ``nlon`` points at longitudes ``φ_k = 2πk/nlon`` (need
``nlon ≥ 2·lmax + 1``).

- ``"gauss"``: Gauss–Legendre colatitudes; exact for ``nlat ≥ lmax + 1``.
- ``"equiangular"``: ``θ_j = πj/(nlat − 1)``, both poles included; exact for
  ``nlat ≥ lmax + 2`` (each Fourier order is resampled exactly onto Gauss–Legendre
  rings, as ducc0 does, rather than integrated with equiangular weights, which would
  only be exact to about nlat/2).

NaN or inf in a map propagates into that map's coefficients (the transform is linear);
other maps of the batch are unaffected.

Examples
--------
>>> import numpy as np
>>> from frenbrdf.numerics.sht import SHT
>>> sht = SHT(nlat=90, nlon=180, lmax=89)
>>> maps = sht.synthesis(np.random.default_rng(0).normal(size=(4, sht.n_coefficients)))
>>> maps.shape
(4, 90, 180)
>>> np.allclose(sht.analysis(maps), sht.analysis(maps))
True
"""

from __future__ import annotations

import numpy as np

from .. import _native

GRIDS = ("gauss", "equiangular")
#: The largest band limit and grid a plan accepts (lmax 4095 is tested; tables grow as lmax²).
MAX_LMAX, MAX_POINTS = 8191, 1 << 28
DTYPES = ("float64", "float32")


class SHT:
    """A transform plan: grid, FFTs and Legendre tables, built once and reused.

    Parameters
    ----------
    nlat, nlon
        Rings and points per ring.
    lmax
        Band limit: degrees 0 … lmax.
    grid
        ``"gauss"`` (Gauss–Legendre) or ``"equiangular"``.
    dtype
        ``"float64"`` or ``"float32"``: the precision the transform runs in. Inputs are
        converted to it.

    Raises
    ------
    ValueError
        Negative lmax, ``nlon < 2·lmax + 1``, too few rings for exact quadrature, or an
        unknown grid or dtype.
    """

    def __init__(self, nlat: int, nlon: int, lmax: int, grid: str = "gauss", dtype: str = "float64"):
        for name, value in (("nlat", nlat), ("nlon", nlon), ("lmax", lmax)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ValueError(f"{name} must be an integer, got {value!r}")
        if lmax < 0:
            raise ValueError(f"lmax = {lmax} must be ≥ 0")
        if nlat < 1 or nlon < 1:
            raise ValueError(f"the grid needs at least one ring and one point per ring, got {nlat} × {nlon}")
        if lmax > MAX_LMAX or nlat * nlon > MAX_POINTS:  # checked before the native core allocates its tables
            raise ValueError(f"lmax = {lmax} on {nlat} × {nlon} points is beyond this library's transforms: "
                             f"lmax ≤ {MAX_LMAX} and nlat · nlon ≤ {MAX_POINTS:,}")
        dtype = np.dtype(dtype).name if dtype in (np.float32, np.float64) else dtype
        if grid not in GRIDS:
            raise ValueError(f"grid must be one of {GRIDS}, got {grid!r}")
        if dtype not in DTYPES:
            raise ValueError(f"dtype must be one of {DTYPES}, got {dtype!r}")
        self.nlat, self.nlon, self.lmax, self.grid, self.dtype = int(nlat), int(nlon), int(lmax), grid, np.dtype(dtype)
        self._plan = _native.ShtPlan(self.nlat, self.nlon, self.lmax, grid, dtype)

    @property
    def n_coefficients(self) -> int:
        return (self.lmax + 1) ** 2

    @property
    def theta(self) -> np.ndarray:
        """Ring colatitudes, ``(nlat,)``."""
        return self._plan.rings()[0]

    @property
    def weights(self) -> np.ndarray:
        """Ring quadrature weights (Gauss–Legendre, or Clenshaw–Curtis on the equiangular
        grid), summing to 2; a grid point's area weight is ``weights[j] · 2π / nlon``."""
        return self._plan.rings()[1]

    def _batched(self, name: str, array, tail: tuple[int, ...]) -> tuple[np.ndarray, tuple[int, ...]]:
        array = np.asarray(array)
        if array.shape[array.ndim - len(tail):] != tail or array.ndim < len(tail):
            shape = ", ".join(map(str, tail))
            raise ValueError(f"{name} must have shape (..., {shape}), got {array.shape}")
        if not (np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)):
            raise ValueError(f"{name} must hold real numbers, got dtype {array.dtype}")
        leading = array.shape[: array.ndim - len(tail)]
        flat = np.ascontiguousarray(array.reshape(-1, int(np.prod(tail))), dtype=self.dtype)
        return flat, leading

    def analysis(self, maps) -> np.ndarray:
        """Maps ``(..., nlat, nlon)`` → coefficients ``(..., (lmax+1)²)``."""
        flat, leading = self._batched("maps", maps, (self.nlat, self.nlon))
        return self._plan.analysis(flat).reshape(*leading, self.n_coefficients)

    def synthesis(self, coefficients) -> np.ndarray:
        """Coefficients ``(..., (lmax+1)²)`` → maps ``(..., nlat, nlon)``."""
        flat, leading = self._batched("coefficients", coefficients, (self.n_coefficients,))
        return self._plan.synthesis(flat).reshape(*leading, self.nlat, self.nlon)

    def analysis_adjoint(self, coefficients) -> np.ndarray:
        """The transpose of :meth:`analysis`: coefficients → maps, with
        ``⟨analysis(x), c⟩ = ⟨x, analysis_adjoint(c)⟩``. The backward pass of analysis."""
        flat, leading = self._batched("coefficients", coefficients, (self.n_coefficients,))
        return self._plan.analysis_adjoint(flat).reshape(*leading, self.nlat, self.nlon)

    def degrees_orders(self) -> np.ndarray:
        """``((lmax+1)², 2)`` int64: (l, m) of every coefficient, sine parts as −m."""
        return self._plan.degrees_orders()

    def to_complex(self, coefficients) -> np.ndarray:
        """Real coefficients ``(..., (lmax+1)²)`` → complex ``(..., lmax+1, lmax+1)`` indexed
        ``[l, m]`` (zero for m > l), in the ducc0 / torch-harmonics convention."""
        flat, leading = self._batched("coefficients", coefficients, (self.n_coefficients,))
        l, m = self.degrees_orders().T
        sign = np.where(m % 2 == 0, 1.0, -1.0) / np.where(m == 0, 1.0, np.sqrt(2.0))
        out = np.zeros((flat.shape[0], self.lmax + 1, self.lmax + 1), dtype=np.result_type(self.dtype, np.complex64))
        cosine, sine = m >= 0, m < 0
        out[:, l[cosine], m[cosine]] += flat[:, cosine] * sign[cosine]
        out[:, l[sine], -m[sine]] += -1j * flat[:, sine] * sign[sine]
        return out.reshape(*leading, self.lmax + 1, self.lmax + 1)

    def from_complex(self, alm) -> np.ndarray:
        """Inverse of :meth:`to_complex`. Imaginary parts of the m = 0 terms are ignored."""
        alm = np.asarray(alm)
        tail = (self.lmax + 1, self.lmax + 1)
        if alm.shape[alm.ndim - 2:] != tail:
            raise ValueError(f"alm must have shape (..., {tail[0]}, {tail[1]}), got {alm.shape}")
        leading = alm.shape[:-2]
        flat = alm.reshape(-1, *tail)
        l, m = self.degrees_orders().T
        scale = np.where(m % 2 == 0, 1.0, -1.0) * np.where(m == 0, 1.0, np.sqrt(2.0))
        values = np.where(m >= 0, flat[:, l, np.abs(m)].real, -flat[:, l, np.abs(m)].imag) * scale
        return values.astype(self.dtype).reshape(*leading, self.n_coefficients)

    def __repr__(self) -> str:
        return f"SHT(nlat={self.nlat}, nlon={self.nlon}, lmax={self.lmax}, grid={self.grid!r}, dtype={self.dtype.name!r})"
