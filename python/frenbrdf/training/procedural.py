"""Procedural training materials: analytic BRDFs drawn afresh, evaluated at MERL bins and at the
SHT nodes of L_fre.

A procedural material is drawn by :func:`frenbrdf.data.synth.draw_material` (random kind, colours,
roughness, Fresnel, layers) and evaluated exactly with :func:`frenbrdf.data.analytic.evaluate`:

- at sampled MERL bins (:func:`values_at_bins`), the samples the encoder and L_rec see, mapped
  with the run's mapping;
- at the SHT grid nodes of each θ_h slice of L_fre (:class:`NodeTruth`), its true coefficients.
  The tables' truth (:class:`frenbrdf.models.losses.FrequencyTruth`) interpolates measured bins onto
  the nodes; here the nodes are evaluated directly, with the same folding: φ_h = 0,
  φ_d ∈ [π, 2π) by reciprocity (exact for an isotropic BRDF), θ_d > π/2 mirrored or zero as
  ``extension`` says. Nodes whose directions fall below the horizon (no MERL bin there) take
  the value at the nearest bin above it, as the kNN of the tables does.
"""

from __future__ import annotations

import numpy as np
import torch

from ..data.analytic import AnalyticMaterial, evaluate
from ..data.synth import draw_material
from ..io.merl import merl_above_horizon, merl_bin_angles, merl_lookup_directions
from ..io.sampling import bin_directions
from ..models.frequency_fit import ValueSpace
from ..models.losses import FrequencyLossConfig, FrequencyTruth
from ..models.mapping import LogRelativeMapping
from ..numerics.coords import rusinkiewicz_to_directions
from ..numerics.knn import KnnInterpolator
from ..numerics.sht import SHT


def draw_procedural(generator: torch.Generator) -> AnalyticMaterial:
    """One random analytic material, every choice seeded from ``generator`` (so from the run's seed)."""
    seed = int(torch.randint(0, 2 ** 62, (1,), generator=generator))
    return draw_material(np.random.default_rng(seed), name="procedural-{label}-{kind}")


def values_at_bins(material: AnalyticMaterial, bins: torch.Tensor, mapping: LogRelativeMapping,
                   reference: torch.Tensor) -> torch.Tensor:
    """Mapped values ``(n, 3)`` float32 of a material at flat bin indices; ``reference`` is f_ref at them."""
    wi, wo = bin_directions(bins)
    return mapping.forward(torch.from_numpy(evaluate(material, wi, wo)).float(), reference)


def _reference_at(mapping: LogRelativeMapping, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """f_ref at direction pairs, trilinear over the bins above the horizon only.

    f_ref is 0 at the bins below the horizon (no material has data there); marking them
    missing keeps near-grazing nodes from averaging those zeros in.
    """
    if not mapping.per_bin:
        return mapping.reference_at(wi, wo)
    reference = mapping.reference.copy()
    reference[:, ~merl_above_horizon()] = -1.0
    return np.maximum(merl_lookup_directions(reference, wi, wo, method="trilinear"), 0.0)


def _directions(theta_h: float, theta_d: np.ndarray, phi_d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ω_i, ω_o) of Rusinkiewicz angles with φ_h = 0."""
    return rusinkiewicz_to_directions(np.stack([np.full_like(theta_d, theta_h), np.zeros_like(theta_d), theta_d,
                                                phi_d], axis=-1))


def _unit(theta, phi) -> np.ndarray:
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


class NodeTruth:
    """True SH coefficients ``(S, 3, ncoeff)`` of analytic materials, evaluated exactly at the SHT nodes.

    The node geometry (folded directions, f_ref at them, which node fills which) is computed
    once per frequency config and mapping; each material then costs one evaluation at
    S × (nodes above the horizon) direction pairs and one SHT analysis.
    """

    def __init__(self, config: FrequencyLossConfig, mapping: LogRelativeMapping):
        self.config, self.mapping = config, mapping
        self.values = ValueSpace(config.values, mapping)
        self.fit = FrequencyTruth(config, mapping=mapping)  # for its coefficients_from_maps: the variant's fit
        self.sht = SHT(config.nlat, config.nlon, config.lmax, config.grid, "float64")
        theta, phi = np.meshgrid(self.sht.theta, 2 * np.pi * np.arange(config.nlon) / config.nlon, indexing="ij")
        theta, phi = theta.reshape(-1), phi.reshape(-1)
        south = np.cos(theta) < -1e-12
        folded = np.where(south, np.pi - theta, theta)  # mirror extension; "zero" overwrites these below
        _, bin_theta_d, bin_phi_d = merl_bin_angles()
        bin_theta_d, bin_phi_d = (a.reshape(-1) for a in np.meshgrid(bin_theta_d, bin_phi_d, indexing="ij"))
        bins_above = merl_above_horizon().reshape(90, -1)
        wi_all: list[np.ndarray] = []
        wo_all: list[np.ndarray] = []
        self.sources: list[np.ndarray] = []
        for i in config.slices:
            theta_h = merl_bin_angles()[0][i]
            wi, wo = _directions(theta_h, folded, phi)
            above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
            # A node below the horizon takes the value at the nearest bin above it (chordal
            # distance of the difference directions, φ_d and φ_d + π alike), as the tables'
            # kNN truth does.
            bins = np.flatnonzero(bins_above[i])
            if len(bins) == 0:
                raise ValueError(f"θ_h slice {i} holds no bin above the horizon; choose other frequency-loss slices")
            bin_d = _unit(bin_theta_d[bins], bin_phi_d[bins])
            nearest = KnnInterpolator(np.concatenate([bin_d, bin_d * [-1, -1, 1]]), _unit(folded[~above], phi[~above]),
                                      1, 1.0).indices.reshape(-1) % len(bins)
            theta_d, phi_d = folded.copy(), phi.copy()
            theta_d[~above], phi_d[~above] = bin_theta_d[bins[nearest]], bin_phi_d[bins[nearest]]
            wi, wo = _directions(theta_h, theta_d, phi_d)
            source = np.arange(len(folded)) + sum(len(w) for w in wi_all)
            if config.extension == "zero":
                source = np.where(south, -1, source)
            wi_all.append(wi)
            wo_all.append(wo)
            self.sources.append(source)
        self.wi, self.wo = np.concatenate(wi_all), np.concatenate(wo_all)
        self.reference = _reference_at(mapping, self.wi, self.wo)

    def maps(self, material: AnalyticMaterial) -> np.ndarray:
        """The material's slices on the grid in the variant's values (mapped by default), ``(S, 3, nlat, nlon)``."""
        mapped = self.values.from_mapped(self.mapping.forward(evaluate(material, self.wi, self.wo), self.reference))
        mapped = np.concatenate([mapped, np.zeros((1, 3))])  # row −1: the zero extension
        grids = np.stack([mapped[source] for source in self.sources])  # (S, nlat·nlon, 3)
        return grids.transpose(0, 2, 1).reshape(len(self.sources), 3, self.config.nlat, self.config.nlon)

    def coefficients(self, material: AnalyticMaterial) -> torch.Tensor:
        """``(S, 3, ncoeff)`` float32."""
        return torch.from_numpy(self.fit.coefficients_from_maps(self.maps(material)).astype(np.float32))
