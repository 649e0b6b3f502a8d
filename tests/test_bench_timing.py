"""benches/common.py's interleaved timing, on a fake clock: who runs when, and the ratios it reports."""

from __future__ import annotations

import pytest

from .conftest import script_module


@pytest.fixture
def fake_clock(monkeypatch):
    """benches/common's clock, advanced only by the contenders and by sleeps; returns (common, clock)."""
    common = script_module("common")
    clock = {"now": 0.0, "slept": 0.0}
    monkeypatch.setattr(common.time, "perf_counter", lambda: clock["now"])

    def sleep(seconds):
        clock["now"] += seconds
        clock["slept"] += seconds

    monkeypatch.setattr(common.time, "sleep", sleep)
    return common, clock


def test_interleaved_rounds_alternate_and_give_per_round_ratios(fake_clock):
    common, clock = fake_clock
    calls = []
    durations = {"first": [1.0, 0.5, 2.0] * 20, "second": [3.0, 1.5, 6.0] * 20}

    def contender(name):
        def call():
            calls.append(name)
            clock["now"] += durations[name].pop(0)
        return call

    timing = common.time_interleaved(contender("first"), contender("second"), rounds=4, calls=3, pause_s=0.25)
    # A warm-up call of each, then rounds of three calls of each, the order swapped every round.
    assert calls[:2] == ["first", "second"]
    blocks = [calls[k] for k in range(2, len(calls), 3)]
    assert blocks == ["first", "second", "second", "first", "first", "second", "second", "first"]
    assert all(calls[k] == calls[k + 1] == calls[k + 2] for k in range(2, len(calls), 3))
    assert clock["slept"] == pytest.approx(8 * 0.25)
    summary = timing.ratio_summary()
    assert summary["rounds"] == 4 and len(timing.first_s) == len(timing.second_s) == 4
    # Each round keeps the fastest of its three calls; the second contender is 3x slower in every round.
    assert summary["median"] == pytest.approx(3.0) and summary["range"] == pytest.approx([3.0, 3.0])
    assert summary["first_median_s"] == pytest.approx(0.5) and summary["second_median_s"] == pytest.approx(1.5)


def test_interleaved_ratio_follows_the_rounds_not_the_drift(fake_clock):
    """A machine whose calls take half as long again, then twice, ... as long each round: each round's ratio stays 2."""
    common, clock = fake_clock
    calls = {"count": 0}

    def contender(seconds):
        def call():
            # Two warm-up calls, then rounds of six calls (three of each contender).
            round_ = max(0, calls["count"] - 2) // 6
            clock["now"] += seconds * (1.0 + 0.5 * round_)
            calls["count"] += 1
        return call

    timing = common.time_interleaved(contender(1.0), contender(2.0), rounds=5, calls=3, pause_s=0)
    assert timing.first_s == pytest.approx([1.0, 1.5, 2.0, 2.5, 3.0])  # the absolute times drifted threefold
    assert timing.ratios == pytest.approx([2.0] * 5)
    assert timing.ratio_summary()["median"] == pytest.approx(2.0)


def test_interleaved_summary_of_one_and_two_rounds_stays_within_their_range():
    common = script_module("common")
    one = common.Interleaved([1.0], [2.0]).ratio_summary()
    assert one["median"] == one["quartiles"][0] == one["quartiles"][1] == 2.0
    two = common.Interleaved([1.0, 1.0], [1.0, 2.0]).ratio_summary()
    assert two["range"] == [1.0, 2.0] and 1.0 <= two["quartiles"][0] <= two["quartiles"][1] <= 2.0
    with pytest.raises(ValueError, match="rounds and calls must be at least 1"):
        common.time_interleaved(lambda: None, lambda: None, rounds=0)
