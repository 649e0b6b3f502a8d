"""The training losses: L_rec (paper Eq. 1), the regularisers and L_fre (docs/method.md §5, §6).

All values are in the mapped space of :mod:`frenbrdf.models.mapping`. :class:`LossConfig`
weights the terms; they are composed in one place, :func:`frenbrdf.training.step.loss_terms`:

    L = L_rec + λ1 · weights + λ2 · latents + η · L_fre

The frequency loss treats each of S half-angle slices θ_h of a BRDF as a function of the
difference direction D on the sphere, g_s(D), and compares spherical-harmonic
coefficients of the truth and of the decoded NBRDF:

- φ_d ∈ [π, 2π) is filled by reciprocity, f(φ_d + π) = f(φ_d);
- below the equator (θ_d > π/2, outside the measured domain) g is extended evenly,
  θ_d → π − θ_d (``extension="mirror"``), or set to 0 (``"zero"``);
- truth: the material's valid MERL bins of the slice are scattered points on the sphere,
  interpolated onto the SHT grid by kNN Gaussian weights (chordal distance, paper Eq. 5;
  weights computed once per slice and reused for every material), then analysed;
- prediction: the NBRDF evaluated at the grid nodes, analysed by the differentiable SHT.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch
from torch import nn

from ..io.atomic import atomic_path
from ..io.merl import SHAPE, merl_bin_angles
from ..numerics.knn import KnnInterpolator
from ..numerics.sht import SHT
from ..numerics.sht_torch import SHTAnalysis
from ..presets import FREQUENCY_VARIANTS, frequency_overrides
from .frequency_fit import FITS, VALUES, TorchMeasuredFit, ValueSpace, measured_fit
from .nbrdf import nbrdf_forward


def reconstruction_loss(predicted: torch.Tensor, true: torch.Tensor, cos_in: torch.Tensor,
                        kind: str = "l1") -> torch.Tensor:
    """Mean cosine-weighted error over samples and channels: L1 (paper Eq. 1) or MSE (HyperBRDF).

    ``predicted``, ``true`` ``(B, N, 3)``; ``cos_in`` ``(B, N)``.
    """
    error = (predicted - true) * cos_in.unsqueeze(-1)
    return error.abs().mean() if kind == "l1" else error.square().mean()


@torch.no_grad()
def samples_loss(params: list[torch.Tensor], coords: torch.Tensor, values: torch.Tensor, cos_in: torch.Tensor,
                 kind: str = "l1", chunk: int = 1 << 16) -> float:
    """:func:`reconstruction_loss` of the NBRDF ``params`` (one material's) on all its samples, in chunks (a whole
    MERL table is 1.1 million): ``coords`` ``(1, N, 6)``, ``values`` ``(1, N, 3)``, ``cos_in`` ``(1, N)``."""
    total, count = 0.0, coords.shape[1]
    for start in range(0, count, chunk):
        rows = slice(start, min(start + chunk, count))
        error = reconstruction_loss(nbrdf_forward(params, coords[:, rows]), values[:, rows], cos_in[:, rows], kind)
        total += float(error) * (rows.stop - start)
    return total / count


def weight_penalty(params: list[torch.Tensor], kind: str = "per_tensor") -> torch.Tensor:
    """The NBRDF weights' penalty, averaged over materials.

    ``"per_tensor"``: Σ over the tensors of each one's mean squared weight (ours);
    ``"all"``: the mean squared weight over all of them together (HyperBRDF's main.py).
    """
    zero = params[0].new_zeros(())  # a tensor to start the sums, on the parameters' device
    if kind == "all":
        return sum((p.square().sum() for p in params), zero) / sum(p.numel() for p in params)
    return sum((p.square().mean() for p in params), zero)


def latent_penalty(z: torch.Tensor) -> torch.Tensor:
    """Mean squared latent."""
    return z.square().mean()


# --------------------------------------------------------------------------- frequency loss


SPHERE_AREA = 4 * math.pi
#: The highest band limit L_fre takes (a config read from a file is checked before any table is built): the SHT of
#: the whole sphere (``fit="sphere"``) costs memory ∝ lmax², 0.8 GB for ``frenbrdf spectrum`` at 511.
MAX_LMAX = 511
#: The highest band limit of the fit to the measured nodes (``fit="measured"``): its operator is a dense matrix of
#: about (lmax + 1)⁴ / 4 numbers per slice, built with a few copies, so memory grows as lmax⁴ (measured peak of
#: ``frenbrdf spectrum``: 1.6 GB at 80, 2.9 GB at 100; it would be 30 GiB at 300).
MAX_MEASURED_LMAX = 80


def spectral_distance(predicted, true, weights=None):
    """L_fre's value between coefficients ``(..., ncoeff)`` (numpy or torch).

    The mean over the leading axes (materials, slices, channels) of Σ_lm (c − c')² / 4π:
    by Parseval, the mean squared difference of the two band-limited functions over the
    sphere, so its scale depends neither on lmax nor on the grid (docs/method.md §5).
    ``weights`` ``(ncoeff,)``: each coefficient's weight (:func:`degree_weights`; None: 1).
    """
    squared = (predicted - true) ** 2
    return (squared if weights is None else squared * weights).sum(-1).mean() / SPHERE_AREA


def degree_weights(lmax: int, power: float) -> np.ndarray:
    """``((lmax + 1)²,)``: (l + 1)^power for each coefficient of degree l (SHT layout)."""
    degrees = SHT(lmax + 1, 2 * lmax + 2, lmax).degrees_orders()[:, 0]
    return (degrees + 1.0) ** power


@dataclass
class FrequencyLossConfig:
    """Settings of L_fre (docs/method.md §5)."""

    lmax: int = 49
    """Band limit of the spherical-harmonic expansion."""
    grid: str = "gauss"
    """SHT grid: ``"gauss"`` (nlat = lmax + 1) or ``"equiangular"`` (nlat = lmax + 2); nlon = 2 lmax + 2."""
    slices: tuple[int, ...] = (0, 24, 48, 72)
    """θ_h slices as MERL θ_h bin indices (0 … 89, θ_h = (i/90)² · 90°: 0°, 6.4°, 25.6°, 57.6°).
    The cost of L_fre grows linearly with their number: four keep it within 30 % of a
    training step at the default sizes (``research/studies/train_step.py``; eight cost 53 %)."""
    k: int = 2
    """Neighbours of the kNN interpolation of the truth."""
    sigma: float = 0.05
    """Gaussian width (chordal distance) of the kNN weights."""
    extension: str = "mirror"
    """Below the equator: ``"mirror"`` (θ_d → π − θ_d) or ``"zero"`` (``fit="sphere"`` only)."""
    fit: str = "sphere"
    """``"sphere"``: the SHT of the whole sphere, below the horizon filled by the extension (the paper);
    ``"measured"``: a damped least-squares fit to the nodes where the data are, so nothing below the
    horizon is compared (:class:`frenbrdf.models.frequency_fit.MeasuredFit`)."""
    damping: float = 1e-2
    """λ of the ``"measured"`` fit, relative to the concentration eigenvalues of the measured region (≤ 1). Smaller
    values fit more of the region's edge and amplify the truth's interpolation error there: on MERL-derived
    materials the floor is 0.3 % of L_fre at 1e-2 and 2 % at 1e-3 (research/frequency.md, "Variants")."""
    values: str = "mapped"
    """What the spectrum is of: ``"mapped"`` (the model's log-relative values, the paper), ``"linear"``
    (reflectance f) or ``"log1p"`` (ln(1 + f): linear for diffuse values, logarithmic in a specular peak)."""
    degree_power: float = 0.0
    """Each squared coefficient difference of degree l counts (l + 1)^degree_power times (0: all alike)."""
    variant: str = "paper"
    """The :data:`frenbrdf.presets.FREQUENCY_VARIANTS` entry these values came from (set by
    :func:`frequency_variant` and ``config_for(frequency=…)``; "custom" for values set by hand). A label:
    what is computed follows the fields above."""

    def __post_init__(self):
        self.slices = tuple(int(s) for s in self.slices)
        problems = []
        if not 1 <= self.lmax <= MAX_LMAX:
            problems.append(f"lmax must lie in 1 … {MAX_LMAX}, got {self.lmax} (L_fre evaluates every NBRDF of a batch "
                            "at (lmax + 1)² nodes per slice; the default is 49)")
        elif self.fit == "measured" and self.lmax > MAX_MEASURED_LMAX:
            problems.append(f"lmax must lie in 1 … {MAX_MEASURED_LMAX} with fit 'measured', got {self.lmax} (the fit "
                            "to the measured nodes is a dense matrix of about (lmax + 1)⁴ / 4 numbers per slice: 1.6 GB "
                            f"at {MAX_MEASURED_LMAX}; fit 'sphere' takes lmax up to {MAX_LMAX})")
        if self.grid not in ("gauss", "equiangular"):
            problems.append(f"grid must be 'gauss' or 'equiangular', got {self.grid!r}")
        if not self.slices or min(self.slices) < 0 or max(self.slices) >= SHAPE[1] or len(set(self.slices)) != len(
                self.slices):
            problems.append(f"slices must be distinct θ_h bin indices in 0 … {SHAPE[1] - 1}, got {self.slices}")
        if not 1 <= self.k <= 64:
            problems.append(f"k must lie in 1 … 64, got {self.k}")
        if not (self.sigma > 0 and np.isfinite(self.sigma)):
            problems.append(f"sigma must be a positive number, got {self.sigma}")
        if self.extension not in ("mirror", "zero"):
            problems.append(f"extension must be 'mirror' or 'zero', got {self.extension!r}")
        if self.fit not in FITS:
            problems.append(f"fit must be one of {FITS}, got {self.fit!r}")
        if self.values not in VALUES:
            problems.append(f"values must be one of {VALUES}, got {self.values!r}")
        if not (0 < self.damping < 1 and np.isfinite(self.damping)):
            problems.append(f"damping must lie in (0, 1), got {self.damping}")
        if not (np.isfinite(self.degree_power) and -4 <= self.degree_power <= 4):
            problems.append(f"degree_power must lie in [−4, 4], got {self.degree_power}")
        if self.variant not in (*FREQUENCY_VARIANTS, "custom"):
            problems.append(f"variant must be one of {(*FREQUENCY_VARIANTS, 'custom')}, got {self.variant!r}")
        if problems:
            raise ValueError("frequency loss: " + "; ".join(problems))

    @property
    def nlat(self) -> int:
        return self.lmax + 1 if self.grid == "gauss" else self.lmax + 2

    @property
    def nlon(self) -> int:
        return 2 * self.lmax + 2

    def truth_settings(self) -> dict:
        """The settings the true coefficients depend on (the cache key's): the paper's fields, and those of a
        variant only where they differ from the paper's, so that the paper's cached truth keeps its key."""
        settings = {key: value for key, value in asdict(self).items()
                    if key not in ("fit", "damping", "values", "degree_power", "variant")}
        if self.fit != "sphere":
            settings.update(fit=self.fit, damping=self.damping)
        if self.values != "mapped":
            settings["values"] = self.values
        return settings


def frequency_variant(name: str, **overrides) -> FrequencyLossConfig:
    """The settings of a named L_fre variant (:data:`frenbrdf.presets.FREQUENCY_VARIANTS`), other fields
    at their defaults or ``overrides``."""
    return FrequencyLossConfig(**{**frequency_overrides(name), **overrides})


def _unit(theta, phi) -> np.ndarray:
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


class FrequencyLoss(nn.Module):
    """L_fre between decoded NBRDFs and precomputed true coefficients.

    ``forward(params, true)``: NBRDF parameters of B materials and their true
    coefficients ``(B, S, 3, ncoeff)`` → :func:`spectral_distance`. ``mapping``: the run's mapping,
    needed by the variants whose spectrum is of reflectance (``config.values``).
    """

    degree_weights: torch.Tensor | None  # buffers (register_buffer)
    node_coords: torch.Tensor

    def __init__(self, config: FrequencyLossConfig, mapping=None):
        super().__init__()
        self.config = config
        self.values = ValueSpace(config.values, mapping)
        self.fit = (TorchMeasuredFit(measured_fit(config.lmax, config.grid, config.slices, config.damping))
                    if config.fit == "measured" else None)
        weights = None if config.degree_power == 0 else torch.from_numpy(
            degree_weights(config.lmax, config.degree_power).astype(np.float32))
        self.register_buffer("degree_weights", weights, persistent=False)
        self.sht = SHTAnalysis(config.nlat, config.nlon, config.lmax, config.grid)
        theta = SHT(config.nlat, config.nlon, config.lmax, config.grid).theta
        # Both grids are symmetric about the equator, and nlon is even: the folded function
        # (φ_d mod π, θ_d mirrored) is fixed by its values on the northern rings (equator
        # included) at φ ∈ [0, π). Evaluate the NBRDF there only and copy.
        if not np.allclose(theta[::-1], np.pi - theta, atol=1e-12):
            raise AssertionError("SHT rings are not symmetric about the equator")
        self.n_north = (config.nlat + 1) // 2
        phi = 2 * np.pi * np.arange(config.nlon // 2) / config.nlon
        directions = _unit(*np.meshgrid(theta[:self.n_north], phi, indexing="ij")).reshape(-1, 3)
        theta_h = merl_bin_angles()[0][list(config.slices)]
        half = _unit(theta_h, np.zeros_like(theta_h))  # φ_h = 0
        coords = np.concatenate([np.repeat(half, len(directions), axis=0), np.tile(directions, (len(half), 1))], axis=1)
        self.register_buffer("node_coords", torch.from_numpy(coords.astype(np.float32)), persistent=False)

    def predicted_maps(self, params: list[torch.Tensor]) -> torch.Tensor:
        """The decoded NBRDFs on the SHT grid: ``(B, S, 3, nlat, nlon)``."""
        return self.maps_from_nodes(nbrdf_forward(params, self.node_coords.expand(params[0].shape[0], -1, -1)))

    def maps_from_nodes(self, values: torch.Tensor) -> torch.Tensor:
        """Mapped values at the (H, D) pairs of ``node_coords`` ``(B, S·nodes, 3)`` → maps on the SHT grid
        ``(B, S, 3, nlat, nlon)``: φ_d + π copied by reciprocity, the southern rings by the extension."""
        batch, n_slices, config = values.shape[0], len(self.config.slices), self.config
        north = values.reshape(batch, n_slices, self.n_north, config.nlon // 2, 3).permute(0, 1, 4, 2, 3)
        north = torch.cat([north, north], dim=-1)  # φ + π: reciprocity
        n_south = config.nlat - self.n_north
        if config.extension == "mirror":
            south = north[..., :n_south, :].flip(-2)  # θ → π − θ
        else:
            south = north.new_zeros(*north.shape[:-2], n_south, config.nlon)
        return torch.cat([north, south], dim=-2)

    def coefficients_from_nodes(self, values: torch.Tensor) -> torch.Tensor:
        """Mapped values at ``node_coords`` ``(B, S·nodes, 3)`` → coefficients ``(B, S, 3, ncoeff)``, as the
        variant takes them (``config.values``, ``config.fit``); differentiable."""
        values = self.values.from_mapped(values)
        if self.fit is None:
            return self.sht(self.maps_from_nodes(values))
        return self.fit(values.reshape(values.shape[0], len(self.config.slices), -1, 3))

    def predicted_coefficients(self, params: list[torch.Tensor]) -> torch.Tensor:
        """``(B, S, 3, ncoeff)``, differentiable."""
        return self.coefficients_from_nodes(
            nbrdf_forward(params, self.node_coords.expand(params[0].shape[0], -1, -1)))

    def forward(self, params: list[torch.Tensor], true: torch.Tensor) -> torch.Tensor:
        weights = None if self.degree_weights is None else self.degree_weights.to(true.dtype)
        return spectral_distance(self.predicted_coefficients(params), true, weights)


#: Version of how the cached truth is computed: a change of method bumps it, so old cache files miss.
TRUTH_CACHE_FORMAT = 2


class FrequencyTruth:
    """True SH coefficients of materials, by kNN interpolation + SHT, cached on disk.

    The kNN weights depend only on which bins of a slice hold data, so they are built
    once per (slice, mask) and reused for every material.
    """

    def cache_key(self, material_hash: str, mapping) -> str:
        """The cache name of a material's truth: a hash of all it depends on — the material
        file's content hash, every field of the mapping (f_ref, ε, the offset), every
        frequency setting and :data:`TRUTH_CACHE_FORMAT`."""
        state = mapping.state()
        described = {"format": TRUTH_CACHE_FORMAT, "material": material_hash, "frequency": self.config.truth_settings(),
                     "mapping": {key: value for key, value in state.items() if key != "reference"}}
        digest = hashlib.sha256(json.dumps(described, sort_keys=True).encode())
        digest.update(np.ascontiguousarray(state["reference"]).tobytes())
        return digest.hexdigest()[:32]

    def __init__(self, config: FrequencyLossConfig, cache_dir: str | os.PathLike | None = None, mapping=None):
        self.config = config
        self.values = ValueSpace(config.values, mapping)
        self.sht = SHT(config.nlat, config.nlon, config.lmax, config.grid, "float64")
        theta = self.sht.theta
        phi = 2 * np.pi * np.arange(config.nlon) / config.nlon
        self.nodes = _unit(*np.meshgrid(theta, phi, indexing="ij")).reshape(-1, 3)
        _, theta_d, phi_d = merl_bin_angles()
        theta_d, phi_d = np.meshgrid(theta_d, phi_d, indexing="ij")
        self.bin_directions = _unit(theta_d, phi_d).reshape(-1, 3)  # (90·180, 3), the bins of one slice
        self.cache_dir = Path(cache_dir) if cache_dir is not None else None
        self._interpolators: dict[bytes, tuple[KnnInterpolator, np.ndarray]] = {}

    def _interpolator(self, slice_valid: np.ndarray) -> tuple[KnnInterpolator, np.ndarray]:
        key = hashlib.sha1(np.packbits(slice_valid).tobytes()).digest()
        if key not in self._interpolators:
            bins = np.flatnonzero(slice_valid)
            d = self.bin_directions[bins]
            copies = [d, d * [-1, -1, 1]]  # reciprocity: φ_d + π
            if self.config.extension == "mirror":
                copies += [c * [1, 1, -1] for c in copies]
            sources = np.concatenate(copies)
            self._interpolators[key] = (KnnInterpolator(sources, self.nodes, self.config.k, self.config.sigma),
                                        np.tile(bins, len(copies)))
        return self._interpolators[key]

    def maps(self, mapped: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """One material's slices on the grid: mapped ``(N_BINS, 3)``, valid ``(N_BINS,)`` → ``(S, 3, nlat, nlon)``,
        in the variant's values (``config.values``)."""
        per_slice = SHAPE[2] * SHAPE[3]
        out = np.empty((len(self.config.slices), 3, self.config.nlat, self.config.nlon))
        below = self.nodes[:, 2] < -1e-12
        for s, i in enumerate(self.config.slices):
            rows = slice(i * per_slice, (i + 1) * per_slice)
            slice_valid, slice_values = valid[rows], self.values.from_mapped(mapped[rows].astype(np.float64))
            if not slice_valid.any():
                raise ValueError(f"the material's table holds no valid bin at θ_h index {i}, one of the frequency "
                                 f"loss's slices ({int(valid.sum()):,} valid bins in all, of {valid.size:,}): a table "
                                 "this sparse has no spectrum there (MERL marks missing bins with negative values)")
            interpolator, source_bins = self._interpolator(slice_valid)
            grid_values = interpolator.apply(slice_values[source_bins])  # (nlat·nlon, 3)
            if self.config.extension == "zero":
                grid_values[below] = 0.0
            out[s] = grid_values.T.reshape(3, self.config.nlat, self.config.nlon)
        return out

    def coefficients(self, mapped: np.ndarray, valid: np.ndarray, cache_key: str | None = None) -> np.ndarray:
        """``(S, 3, ncoeff)`` float32, from the disk cache when ``cache_key`` (:meth:`cache_key`) is given
        and present."""
        path = None
        if self.cache_dir is not None and cache_key is not None:
            path = self.cache_dir / f"{cache_key}.npy"
            expected = (len(self.config.slices), 3, self.sht.n_coefficients)
            # A regular file of about the right size only: np.load would block on a FIFO, and allocate what a
            # damaged header declares.
            if path.is_file() and path.stat().st_size <= 4 * math.prod(expected) + 4096:
                try:
                    cached = np.load(path, allow_pickle=False)
                    # An entry is used only if it is what this code writes: the shape, float32, finite. A damaged
                    # or poisoned one (a NaN would stop training as if it diverged) is recomputed and replaced.
                    if cached.shape == expected and \
                            cached.dtype == np.float32 and np.all(np.isfinite(cached)):
                        return cached
                except (OSError, ValueError, EOFError):
                    pass
        coefficients = self.coefficients_from_maps(self.maps(mapped, valid)).astype(np.float32)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            with atomic_path(path) as temporary:
                np.save(temporary, coefficients)
        return coefficients

    def coefficients_from_maps(self, maps: np.ndarray) -> np.ndarray:
        """Grid maps ``(..., S, 3, nlat, nlon)`` → coefficients ``(..., S, 3, ncoeff)`` (float64), by the
        variant's fit: the SHT of the whole sphere, or the fit to the measured nodes."""
        if self.config.fit == "sphere":
            return self.sht.analysis(maps)
        fit = measured_fit(self.config.lmax, self.config.grid, self.config.slices, self.config.damping)
        return fit.coefficients(fit.grid_nodes(maps))


# --------------------------------------------------------------------------- the weights of the terms


@dataclass
class LossConfig:
    """How the loss terms are weighted: L = L_rec + λ1 · weights + λ2 · latents + η · L_fre."""

    kind: str = "l1"
    """Reconstruction error: ``"l1"`` (paper Eq. 1) or ``"mse"`` (HyperBRDF)."""
    lambda_weights: float = 1e-3
    """λ1, on the NBRDF weights' penalty (:func:`weight_penalty`)."""
    weight_penalty: str = "per_tensor"
    """``"per_tensor"``: Σ of each tensor's mean squared weight; ``"all"``: the mean over all weights
    together (HyperBRDF)."""
    lambda_latent: float = 1e-3
    """λ2, on the mean squared latent."""
    eta: float = 5e-4
    """η, the weight of the frequency-rectified loss (0 switches it off). L_fre is normalised on the
    sphere (:func:`spectral_distance`); 5e-4 is the paper's η = 0.1 on its mean over the (lmax + 1)²
    coefficients at lmax 49 (0.1 · 4π / 50² ≈ 5e-4), the strength every earlier result was trained
    with. Training logs ‖∇(η·L_fre)‖ / ‖∇L_rec‖ each epoch (``train_gradient_ratio``): about 1/250
    at this η on the default bank."""
    frequency: FrequencyLossConfig = field(default_factory=FrequencyLossConfig)

    def __post_init__(self):
        if self.kind not in ("l1", "mse"):
            raise ValueError(f"loss.kind must be 'l1' or 'mse', got {self.kind!r}")
        if self.weight_penalty not in ("per_tensor", "all"):
            raise ValueError(f"loss.weight_penalty must be 'per_tensor' or 'all', got {self.weight_penalty!r}")
        for name in ("lambda_weights", "lambda_latent", "eta"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"loss.{name} must be a finite number ≥ 0, got {value}")
