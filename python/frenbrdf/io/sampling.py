"""Samples of a whole material at MERL bins: what an encoder is given of a table or a measurement.

A material is sampled at random measured bins of its MERL table (:func:`valid_bins`, :func:`sample_bins`), at
each bin's pair of directions (:func:`bin_directions`); a measurement (an RGL ``.bsdf``) is evaluated itself there,
each pair in a random order (:func:`truth_samples`). :func:`draw_samples` does all of it and returns the
:class:`~frenbrdf.io.samples.Measurements` that :func:`frenbrdf.io.read_samples` returns for a ``.binary`` or a
``.bsdf``; evaluation, training's validation renders and the viewer draw their samples with the same functions.
"""

from __future__ import annotations

import functools

import numpy as np

from ..numerics.coords import rusinkiewicz_to_directions
from .bsdf import MeasuredBSDF
from .merl import N_BINS, SHAPE, merl_above_horizon, merl_bin_angles
from .samples import Measurements


def as_table(truth: np.ndarray | MeasuredBSDF) -> np.ndarray:
    """The MERL table ``(3, 90, 90, 180)`` of a whole material: a table itself, a measurement at every bin."""
    return truth.table() if isinstance(truth, MeasuredBSDF) else truth


@functools.cache
def _above_horizon() -> np.ndarray:
    """The bins whose directions both lie above the surface, flat ``(N_BINS,)``, read-only (computed once)."""
    above = merl_above_horizon().reshape(-1)
    above.flags.writeable = False
    return above


def valid_bins(table: np.ndarray) -> np.ndarray:
    """The measured bins (flat indices) of a MERL table: valid in every channel and above the horizon (what a
    model may be given; a value stored below the horizon is no measurement).

    Raises ValueError when there is none."""
    bins = np.flatnonzero(np.all(table.reshape(3, N_BINS) >= 0, axis=0) & _above_horizon())
    if len(bins) == 0:
        raise ValueError("the MERL table holds no bin measured in every channel above the horizon")
    return bins


def sample_bins(table: np.ndarray, rng: np.random.Generator, samples: int) -> np.ndarray:
    """``samples`` random measured bins (flat indices, :func:`valid_bins`) of a MERL table, without replacement:
    all of them when the table holds no more (a count is capped at what the data hold)."""
    bins = valid_bins(table)
    if samples < 1:
        raise ValueError(f"samples must be ≥ 1, got {samples}")
    return bins if samples >= len(bins) else rng.choice(bins, size=samples, replace=False)


def bin_directions(bins) -> tuple[np.ndarray, np.ndarray]:
    """(ω_i, ω_o) of flat bin indices (an array or a CPU tensor; φ_h = 0), each ``(len(bins), 3)``.

    The directions of :func:`frenbrdf.merl_bin_directions` at those bins only (the same values, without building
    the whole grid).
    """
    theta_h, theta_d, phi_d = merl_bin_angles()
    i, j, k = np.unravel_index(np.asarray(bins), SHAPE[1:])
    return rusinkiewicz_to_directions(np.stack([theta_h[i], np.zeros(i.shape), theta_d[j], phi_d[k]], axis=-1))


def truth_samples(truth, bins: np.ndarray,
                  rng: np.random.Generator) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """The truth's reflectance at ``bins`` ``(N, 3)`` and the direction pairs ``(ω_i, ω_o)`` it was taken at: what
    an encoder takes.

    ``truth`` as :func:`frenbrdf.io.read_material` returns a measured file. A MERL table gives its values at the
    bins' directions and draws nothing from ``rng``. A measurement (a callable ``m(ω_i, ω_o)``, e.g.
    :class:`frenbrdf.io.bsdf.MeasuredBSDF`) is evaluated at each bin's pair in an order drawn from ``rng``: as the
    bin gives it or reversed (ω_i ↔ ω_o), each with probability ½. A table keeps one order of each pair, as
    reciprocity allows; a real measurement is not reciprocal near grazing (research/measurements.md, "The
    measurements are not reciprocal"), so its other order is a measurement the table lost.
    """
    wi, wo = bin_directions(bins)
    if isinstance(truth, np.ndarray):
        return truth.reshape(3, N_BINS)[:, bins].T, (wi, wo)
    reverse = rng.random(len(bins)) < 0.5
    wi, wo = np.where(reverse[:, None], wo, wi), np.where(reverse[:, None], wi, wo)
    return np.maximum(truth(wi, wo), 0.0), (wi, wo)


def draw_samples(truth: np.ndarray | MeasuredBSDF, *, samples: int | None = 4000, seed: int = 0,
                 source: str = "") -> Measurements:
    """A MERL table, or a measurement, sampled at ``samples`` random valid MERL bins (drawn from ``seed``) or at all
    of them (None). A measurement is evaluated itself at each bin's pair of directions, in an order drawn from
    ``seed`` (:func:`truth_samples`), and is itself kept as the truth to render. ``source``: the file, for the
    result and for messages."""
    if samples is not None and samples < 1:
        raise ValueError(f"samples must be ≥ 1 or all, got {samples}")
    table = as_table(truth)
    rng = np.random.default_rng(seed)
    try:  # more samples than the table holds: all of them (a count is capped at what the data hold)
        bins = valid_bins(table) if samples is None else sample_bins(table, rng, samples)
    except ValueError as error:
        raise ValueError(f"{source}: {error}" if source else str(error)) from None
    values, (wi, wo) = truth_samples(truth, bins, rng)
    kind = "merl" if isinstance(truth, np.ndarray) else "bsdf"
    return Measurements(np.array(values), wi, wo, source, kind, table, truth)
