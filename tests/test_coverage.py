"""Coverage weights (frenbrdf.models.coverage) and `RefineConfig.coverage_k`."""

from __future__ import annotations

import numpy as np
import pytest

from frenbrdf.io.merl import merl_above_horizon
from frenbrdf.io.sampling import bin_directions
from frenbrdf.models.coverage import MAX_K, MAX_WEIGHT, coverage_weights, index_space
from frenbrdf.models.reconstruct import RefineConfig


def random_bins(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    valid = np.flatnonzero(merl_above_horizon())
    return bin_directions(np.random.default_rng(seed).choice(valid, count, replace=False))


def test_random_bins_weigh_about_alike():
    weights = coverage_weights(*random_bins(3000, 1), 32)
    assert weights.mean() == pytest.approx(1.0)
    assert 0.8 < np.median(weights) < 1.2
    assert np.mean((weights > 0.5) & (weights < 2)) > 0.9


def test_a_crowded_region_weighs_less_than_a_thin_one():
    wi, wo = random_bins(4000, 2)
    place = index_space(wi, wo)
    near_mirror = place[:, 0] < 0.3  # θ_h small: the region a device's lights crowd
    keep = near_mirror | (np.random.default_rng(3).random(len(wi)) < 0.1)  # the rest thinned to a tenth
    weights = coverage_weights(wi[keep], wo[keep], 16)
    crowded, thin = weights[near_mirror[keep]], weights[~near_mirror[keep]]
    assert np.median(thin) > 5 * np.median(crowded)
    # clipped at MAX_WEIGHT times the mean, then scaled back to mean 1 (which raises every weight a little)
    assert weights.max() <= 1.2 * MAX_WEIGHT and weights.mean() == pytest.approx(1.0)


def test_too_few_pairs_weigh_alike_and_k_is_checked():
    wi, wo = random_bins(5, 4)
    assert np.array_equal(coverage_weights(wi, wo, 8), np.ones(5))
    for k in (0, -3, 2.5, True, MAX_K + 1):
        with pytest.raises(ValueError, match="k must be an integer from 1"):
            coverage_weights(wi, wo, k)


def test_every_allowed_k_gives_weights_even_the_smallest_and_largest():
    # k = 1 once crashed: scipy returns a flat array for a plain k=1.
    wi, wo = random_bins(1200, 6)
    for k in (1, 2, MAX_K):
        weights = coverage_weights(wi, wo, k)
        assert weights.shape == (1200,) and np.all(np.isfinite(weights)) and weights.mean() == pytest.approx(1.0)


def test_refine_config_checks_coverage_k():
    assert RefineConfig(coverage_k=32).coverage_k == 32
    for k in (-1, 1.5, True, "8", MAX_K + 1):
        with pytest.raises(ValueError, match="coverage_k"):
            RefineConfig(coverage_k=k)


def test_the_queries_in_chunks_give_the_same_weights(monkeypatch):
    from frenbrdf.models import coverage

    wi, wo = random_bins(500, 5)
    whole = coverage_weights(wi, wo, 8)
    monkeypatch.setattr(coverage, "QUERY_VALUES", 50)  # chunks of 5 or 6 pairs
    assert np.array_equal(coverage_weights(wi, wo, 8), whole)


def test_random_bins_leave_no_bin_uncovered_and_a_device_leaves_its_blind_side():
    from frenbrdf.models.coverage import ANCHOR_BINS, uncovered_bins

    bins, remoteness = uncovered_bins(*random_bins(4000, 6))
    assert len(bins) <= 0.01 * ANCHOR_BINS
    wi, wo = random_bins(4000, 7)
    near_mirror = index_space(wi, wo)[:, 0] < 0.4  # what a device that sees only the mirror directions gives
    bins, remoteness = uncovered_bins(wi[near_mirror], wo[near_mirror])
    places = index_space(*bin_directions(bins))
    assert np.all((remoteness > 0) & (remoteness <= 1))
    assert np.all(places[:, 0] > 0.4)  # every uncovered bin lies on the side no pair saw
    assert len(bins) > 0.4 * ANCHOR_BINS and np.mean(remoteness[places[:, 0] > 0.7]) == pytest.approx(1.0)


def test_refine_config_checks_anchor():
    assert RefineConfig(anchor=0.5).anchor == 0.5
    for anchor in (-0.1, float("nan"), 1e9, True, "1"):
        with pytest.raises(ValueError, match="anchor"):
            RefineConfig(anchor=anchor)


def test_the_summary_warns_where_only_the_mirror_reflection_was_sampled():
    from frenbrdf.io.patterns import PATTERNS
    from frenbrdf.models.coverage import MIRROR_ONLY_DEGREES, coverage_summary

    rng = np.random.default_rng(8)
    mirror = coverage_summary(*PATTERNS["specular"](1500, rng))
    assert mirror["largest_half_angle_deg"] < MIRROR_ONLY_DEGREES and 0.3 < mirror["uncovered"] < 0.7
    assert len(mirror["warnings"]) == 1 and "base colour" in mirror["warnings"][0]
    for name in ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "flat-sample"):
        assert coverage_summary(*PATTERNS[name](1500, rng))["warnings"] == [], name
    assert coverage_summary(*random_bins(4000, 9))["uncovered"] < 0.01
