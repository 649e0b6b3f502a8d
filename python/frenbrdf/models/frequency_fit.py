"""What L_fre's spectra are taken of, and how: the parts its variants change (research/frequency.md, "Variants").

The paper's reading (:class:`frenbrdf.models.losses.FrequencyLossConfig` defaults, variant ``"paper"``)
analyses each θ_h slice's *mapped* values on the whole sphere of difference directions, the
part below the horizon filled by an extension of the data. Two settings change that:

``values`` (:class:`ValueSpace`)
    ``"mapped"``: the model's log-relative values (the paper); ``"linear"``: reflectance f;
    ``"log1p"``: ln(1 + f), linear for a diffuse material (f ≪ 1) and logarithmic only in a
    specular peak, so the peak keeps its contrast. Both need the run's mapping (f = its inverse).
``fit`` (:class:`MeasuredFit`)
    ``"sphere"``: the SHT of the whole grid (the paper); ``"measured"``: the coefficients that fit
    the values at the nodes where the data are (θ_d < 90°, ω_i and ω_o above the horizon) in the
    least-squares sense, with a small Tikhonov damping:

        c = argmin Σ_{valid j} w_j (g_j − Σ c_lm Y_lm(j))² + λ Σ c_lm²,

    w_j the quadrature weights. Nothing below the horizon enters, neither the truth's kNN
    extension nor the network's extrapolation: the loss's floor goes. The solution is linear
    in g, c = P g, with P computed once per setting (a dense matrix per slice); the prediction's
    gradient is Pᵀ, exact under autograd. On a part of the sphere the problem is ill-posed
    (the coefficients of functions that vanish on the data are not determined); λ, relative to
    the eigenvalues of the region's concentration matrix (in [0, 1]), damps those.

Both the truth (numpy, float64) and the prediction (torch) use the same P: what is compared is
the same linear functional of the values at the same nodes.
"""

from __future__ import annotations

import functools

import numpy as np
import torch

from ..io.merl import merl_bin_angles
from ..numerics.coords import rusinkiewicz_to_directions
from ..numerics.sht import SHT

#: ``FrequencyLossConfig.values``: the value spaces a spectrum can be taken of.
VALUES = ("mapped", "linear", "log1p")
#: ``FrequencyLossConfig.fit``: how coefficients are obtained from the grid values.
FITS = ("sphere", "measured")


class ValueSpace:
    """Mapped values → the values L_fre takes the spectrum of (:data:`VALUES`).

    Parameters
    ----------
    values
        One of :data:`VALUES`.
    mapping
        The run's :class:`~frenbrdf.models.mapping.LogRelativeMapping`; needed unless ``values`` is
        ``"mapped"``. Only a per-channel f_ref is taken (a per-bin one would need f_ref at every node).
    """

    def __init__(self, values: str = "mapped", mapping=None):
        if values not in VALUES:
            raise ValueError(f"frequency loss: values must be one of {VALUES}, got {values!r}")
        if values != "mapped":
            if mapping is None:
                raise ValueError(f"frequency loss: values {values!r} need the run's mapping (f is its inverse)")
            if mapping.per_bin:
                raise ValueError(f"frequency loss: values {values!r} need a per-channel mapping (mapping.reference "
                                 "'per_channel'), got a per-bin one")
        self.values, self.mapping = values, mapping

    def from_mapped(self, mapped):
        """Mapped values ``(..., 3)`` (numpy or torch) → the spectrum's values, same type and shape."""
        if self.values == "mapped":
            return mapped
        reference = self.mapping.reference
        if isinstance(mapped, torch.Tensor):
            reference = torch.as_tensor(reference, dtype=mapped.dtype, device=mapped.device)
            reflectance = self.mapping.inverse(mapped, reference)
            return reflectance if self.values == "linear" else torch.log1p(reflectance)
        reflectance = self.mapping.inverse(np.asarray(mapped, dtype=np.float64), reference)
        return reflectance if self.values == "linear" else np.log1p(reflectance)


def slice_directions(theta_h: float, theta_d, phi_d) -> tuple[np.ndarray, np.ndarray]:
    """(ω_i, ω_o) of a θ_h slice at difference directions (θ_d, φ_d), φ_h = 0."""
    theta_d, phi_d = np.broadcast_arrays(np.asarray(theta_d, dtype=np.float64), np.asarray(phi_d, dtype=np.float64))
    angles = np.stack([np.full(theta_d.shape, theta_h), np.zeros(theta_d.shape), theta_d, phi_d], axis=-1)
    return rusinkiewicz_to_directions(angles)


class MeasuredFit:
    """The damped least-squares fit of SH coefficients to a slice's values at its measured nodes.

    The nodes are those where L_fre's prediction is evaluated (:class:`~frenbrdf.models.losses.FrequencyLoss`):
    the northern rings (equator included) at φ ∈ [0, π), ring-major, ``U`` of them; φ + π holds the
    same value (reciprocity). A node is measured when θ_d < 90° and both directions of the pair
    lie above the horizon. Reciprocity makes every odd order m vanish on both sides, so only the
    even-m coefficients (``rows``) are fitted; the others are 0.

    Attributes
    ----------
    operators
        ``(S, U, E)`` float64: coefficient e of slice s = Σ_u values[u] · operators[s, u, e]; zero rows at
        the nodes that are not measured.
    rows
        ``(E,)`` the even-m positions in the coefficient layout of :class:`~frenbrdf.numerics.sht.SHT`.
    measured
        ``(S, U)`` bool.
    """

    def __init__(self, lmax: int, grid: str, slices: tuple[int, ...], damping: float):
        nlat = lmax + 1 if grid == "gauss" else lmax + 2
        nlon = 2 * lmax + 2
        sht = SHT(nlat, nlon, lmax, grid, "float64")
        n_north, half = (nlat + 1) // 2, nlon // 2
        self.n_coefficients, self.n_north, self.half = sht.n_coefficients, n_north, half
        self.rows = np.flatnonzero(np.abs(sht.degrees_orders()[:, 1]) % 2 == 0)
        unit = np.zeros((len(self.rows), sht.n_coefficients))
        unit[np.arange(len(self.rows)), self.rows] = 1.0
        basis = sht.synthesis(unit)[:, :n_north, :half].reshape(len(self.rows), -1)  # (E, U)
        # Each node stands for itself and its twin at φ + π: twice its quadrature weight.
        weights = np.repeat(2 * sht.weights[:n_north] * (2 * np.pi / nlon), half)
        theta_d, phi_d = np.meshgrid(sht.theta[:n_north], 2 * np.pi * np.arange(half) / nlon, indexing="ij")
        theta_d, phi_d = theta_d.reshape(-1), phi_d.reshape(-1)
        operators, measured = [], []
        for i in slices:
            wi, wo = slice_directions(merl_bin_angles()[0][i], theta_d, phi_d)
            valid = (np.cos(theta_d) > 1e-12) & (wi[:, 2] > 0) & (wo[:, 2] > 0)
            if not valid.any():
                raise ValueError(f"θ_h slice {i} has no grid node above the horizon; choose other frequency-loss slices")
            weighted = basis * (weights * valid)  # (E, U): Yᵀ W
            normal = weighted @ basis.T + damping * np.eye(len(self.rows))
            operators.append(np.linalg.solve(normal, weighted).T)  # (U, E): P = (YᵀWY + λI)⁻¹ YᵀW
            measured.append(valid)
        self.operators, self.measured = np.stack(operators), np.stack(measured)

    def coefficients(self, values: np.ndarray) -> np.ndarray:
        """Values at the nodes ``(..., S, 3, U)`` → coefficients ``(..., S, 3, ncoeff)`` (float64)."""
        fitted = np.einsum("...scu,sue->...sce", np.asarray(values, dtype=np.float64), self.operators)
        out = np.zeros(fitted.shape[:-1] + (self.n_coefficients,))
        out[..., self.rows] = fitted
        return out

    def grid_nodes(self, maps: np.ndarray) -> np.ndarray:
        """Grid maps ``(..., nlat, nlon)`` → the values at the fit's nodes ``(..., U)``."""
        return maps[..., :self.n_north, :self.half].reshape(*maps.shape[:-2], -1)


@functools.lru_cache(maxsize=4)
def measured_fit(lmax: int, grid: str, slices: tuple[int, ...], damping: float) -> MeasuredFit:
    """:class:`MeasuredFit`, built once per setting (about a second at lmax 49) and shared."""
    return MeasuredFit(lmax, grid, tuple(slices), damping)


class TorchMeasuredFit(torch.nn.Module):
    """:class:`MeasuredFit` on tensors: values at the nodes ``(B, S, U, 3)`` → coefficients ``(B, S, 3, ncoeff)``.

    A fixed linear map (one batched matrix product), so autograd's backward is its exact transpose.
    """

    operators: torch.Tensor  # buffers (register_buffer)
    rows: torch.Tensor

    def __init__(self, fit: MeasuredFit):
        super().__init__()
        self.n_coefficients = fit.n_coefficients
        self.register_buffer("operators", torch.from_numpy(fit.operators.astype(np.float32)), persistent=False)
        self.register_buffer("rows", torch.from_numpy(fit.rows), persistent=False)

    def forward(self, values: torch.Tensor) -> torch.Tensor:
        fitted = torch.einsum("bsuc,sue->bsce", values, self.operators.to(values.dtype))
        out = fitted.new_zeros(*fitted.shape[:-1], self.n_coefficients)
        return out.index_copy(-1, self.rows, fitted)
