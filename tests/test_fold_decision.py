"""The real-measurements fold study's rules (research/studies/measured_folds/decide.py): the measurements and
the procedural families join the training data only when they help the measurements held out of the runs
that judge them and cost the tables nothing beyond noise."""

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

DECIDE = Path(__file__).resolve().parents[1] / "research" / "studies" / "measured_folds" / "decide.py"


@pytest.fixture(scope="module")
def decide():
    spec = importlib.util.spec_from_file_location("measured_folds_decide", DECIDE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rows(gains: dict[str, float], materials: int, group: str) -> list[dict]:
    """Rows of each ``variant/run`` label: encoder PSNR 30 + gain + noise, and a `latent` row that never differs."""
    rng = np.random.default_rng(len(gains) * materials)
    out = []
    for label, gain in gains.items():
        for m in range(materials):
            for budget, psnr in (("none", 30 + gain + rng.normal(0, 0.1)), ("latent", 35.0)):
                out.append({"model": label, "material": f"{group}{m}", "group": group, "draw": 0,
                            "pattern": "merl-bins", "count": 4000, "budget": budget, "psnr": psnr, "delta_e": 2.0})
    return out


def run(decide, tmp_path, measured_gains, table_gains) -> dict:
    for name, gains, group in (("measured", measured_gains, "measured"), ("tables", table_gains, "tables")):
        (tmp_path / name).mkdir()
        (tmp_path / name / "compare.json").write_text(json.dumps({"rows": rows(gains, 19, group)}))
    assert decide.main([str(tmp_path / "measured" / "compare.json"), str(tmp_path / "tables" / "compare.json")]) == 0
    return json.loads((tmp_path / "measured" / "decision.json").read_text())


def test_measurements_and_families_that_help_both_join(decide, tmp_path):
    decision = run(decide, tmp_path, {"fits/s0": 0, "fits/s1": 0, "measured/f0-s0": 2, "families/f0-s0": 3, "v4": 9},
                   {"fits/s0": 0, "measured/f0-s0": 0, "families/f0-s0": 0})
    assert decision["ships"] == ["measurements", "families"]
    assert decision["measurements"]["measurements"]["mean"] == pytest.approx(2, abs=0.1)


def test_a_gain_on_measurements_that_costs_the_tables_is_refused(decide, tmp_path):
    decision = run(decide, tmp_path, {"fits/s0": 0, "measured/f0-s0": 2, "families/f0-s0": 2},
                   {"fits/s0": 0, "measured/f0-s0": -1, "families/f0-s0": -1})
    assert not decision["measurements"]["wins"]
    assert decision["families"]["measurements"]["mean"] == pytest.approx(0, abs=0.1)  # judged against `measured`
    assert decision["ships"] == []


def test_the_replication_tests_families_and_measurements_together_against_fits(decide, tmp_path):
    decision = run(decide, tmp_path, {"fits/s3": 0, "fits/s4": 0, "families/f0-s2": 1.5, "v4": 9},
                   {"fits/s3": 0, "families/f0-s2": 0.2})
    assert set(decision) == {"together", "ships"}
    assert decision["together"]["measurements"]["mean"] == pytest.approx(1.5, abs=0.1)
    assert decision["ships"] == ["together"]
    (tmp_path / "lost").mkdir()
    lost = run(decide, tmp_path / "lost", {"fits/s3": 0, "families/f0-s2": -0.5}, {"fits/s3": 0, "families/f0-s2": 0})
    assert lost["ships"] == []
