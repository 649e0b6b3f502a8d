"""Comparisons over seeds: mean ± sd, paired t-intervals, and what counts as significant."""

from __future__ import annotations

import math

import pytest

from frenbrdf.evaluation.statistics import compare_seeds, markdown, paired_interval


def summaries(nbrdf_offsets, hyper_offsets):
    """Three seeds whose FreNBRDF PSNR varies a lot between seeds (different splits)."""
    base = {0: 28.0, 1: 31.0, 2: 25.0}
    return {seed: {"frenbrdf": {"psnr": value}, "nbrdf": {"psnr": value + nbrdf_offsets[seed]},
                   "hyperbrdf": {"psnr": value + hyper_offsets[seed]}} for seed, value in base.items()}


def test_identical_methods_have_an_interval_containing_zero():
    comparison = compare_seeds(summaries({0: 0.2, 1: -0.3, 2: 0.1}, {0: 0.0, 1: 0.0, 2: 0.0}), ["psnr"])
    nbrdf = comparison["metrics"]["psnr"]["differences"]["nbrdf"]
    assert nbrdf["low"] < 0 < nbrdf["high"] and not nbrdf["significant"]
    same = comparison["metrics"]["psnr"]["differences"]["hyperbrdf"]
    assert same["mean"] == 0 and not same["significant"]


def test_a_consistent_difference_is_significant_though_seeds_vary_more():
    """Pairing within a seed: a steady −2 dB stands out although the seeds' own PSNRs spread by 6 dB."""
    comparison = compare_seeds(summaries({0: 0.0, 1: 0.1, 2: -0.1}, {0: -2.0, 1: -2.2, 2: -1.9}), ["psnr"])
    row = comparison["metrics"]["psnr"]
    hyper = row["differences"]["hyperbrdf"]
    assert hyper["significant"] and hyper["high"] < 0 and hyper["mean"] == pytest.approx(-2.0333, abs=1e-3)
    assert row["methods"]["frenbrdf"]["sd"] == pytest.approx(3.0)
    table = markdown(comparison, {"psnr": "Recon PSNR ↑"})
    assert "**-2.03 [" in table and "28 ± 3" in table and "3 seeds" in table


def test_the_interval_is_the_textbook_t_interval():
    d = [1.0, 2.0, 3.0]
    result = paired_interval(d)
    half = 4.302652729911275 * 1.0 / math.sqrt(3)  # t_{0.975, 2} · sd / √n
    assert (result["low"], result["high"]) == (pytest.approx(2 - half), pytest.approx(2 + half))


def test_one_seed_has_no_interval_and_nothing_is_significant():
    assert paired_interval([5.0]) == {"mean": 5.0, "low": None, "high": None, "n": 1, "significant": False}
    with pytest.raises(ValueError, match="finite"):
        paired_interval([1.0, float("nan")])


def test_seeds_must_hold_the_same_methods():
    broken = summaries({0: 0, 1: 0, 2: 0}, {0: 0, 1: 0, 2: 0})
    del broken[1]["hyperbrdf"]
    with pytest.raises(ValueError, match="same methods"):
        compare_seeds(broken, ["psnr"])


def test_colour_difference_is_compared_like_rmse():
    """ΔE is lower-is-better like RMSE: its row is labelled ↓, and a steadily lower ΔE of a method is a
    significant negative difference, shown exactly as the same RMSE numbers would be."""
    from frenbrdf.evaluation.evaluate import ROWS

    labels = dict(ROWS)
    assert labels["delta_e"].endswith("↓") and labels["edit_delta_e"].endswith("↓") and labels["rmse_x100"].endswith("↓")
    values = summaries({0: -1.0, 1: -1.2, 2: -0.9}, {0: 0.1, 1: -0.2, 2: 0.1})
    both = {s: {m: {"rmse_x100": v["psnr"], "delta_e": v["psnr"]} for m, v in by.items()} for s, by in values.items()}
    comparison = compare_seeds(both, ["rmse_x100", "delta_e"])
    lower = comparison["metrics"]["delta_e"]["differences"]["nbrdf"]
    assert lower["significant"] and lower["high"] < 0
    rmse_row, delta_e_row = markdown(comparison, labels).splitlines()[-2:]
    assert rmse_row.startswith("| Recon RMSE×10² ↓ |") and delta_e_row.startswith("| Recon ΔE ↓ |")
    assert rmse_row.split("|")[2:] == delta_e_row.split("|")[2:] and "**-1.03 [" in delta_e_row
