"""The sampling-patterns study's decision rule (research/studies/sampling_patterns/decide.py) and its merge of
two scorings: the rule chooses what it says, on the tables only."""

import json
from pathlib import Path

import numpy as np
import pytest

STUDY = Path(__file__).resolve().parents[1] / "research" / "studies" / "sampling_patterns"
PATTERNS = ("merl-bins", "uniform", "in-plane", "gonioreflectometer", "image-based", "specular")


@pytest.fixture
def study(monkeypatch):
    monkeypatch.syspath_prepend(str(STUDY))
    monkeypatch.syspath_prepend(str(STUDY.parent))
    import decide
    import merge
    return decide, merge


def rows(gains: dict[str, tuple[float, float]], materials=8, group="tables"):
    """Rows of each ``variant/run``: PSNR 30 + noise + (gain on the instrument patterns, gain on merl-bins)."""
    rng = np.random.default_rng(0)
    out = []
    for label, (instrument_gain, bins_gain) in gains.items():
        for m in range(materials):
            for pattern in PATTERNS:
                gain = bins_gain if pattern == "merl-bins" else instrument_gain
                out.append({"model": label, "material": f"m{m}", "group": group, "draw": 0, "pattern": pattern,
                            "count": 1500, "budget": "none", "psnr": 30 + gain + rng.normal(0, 0.1),
                            "delta_e": 2.0})
    return out


def report(rows_):
    return {"run": {}, "models": {}, "trained_on": [], "rows": rows_}


def test_the_rule_takes_a_mixture_that_helps_the_patterns_and_keeps_random_bins(study, tmp_path):
    decide, _ = study
    path = tmp_path / "compare.json"
    path.write_text(json.dumps(report(rows({"paper-mean/0": (0, 0), "paper-mean/1": (0, 0),
                                            "instruments-mean/0": (3, 0), "instruments-density/0": (3, 0),
                                            "mixed-mean/0": (2, 0), "mixed-density/0": (9, 0),
                                            "paper-density/0": (0, 0)}))))
    assert decide.main([str(path)]) == 0
    decision = json.loads((tmp_path / "decision.json").read_text())
    # both mixtures pass; instruments gains more; its density variant is no better beyond noise
    assert decision["chosen"] == "instruments-mean"
    assert decision["sampling"]["instruments"]["instruments"]["mean"] == pytest.approx(3, abs=0.2)


def test_the_rule_refuses_a_mixture_that_costs_random_bins(study, tmp_path):
    decide, _ = study
    path = tmp_path / "compare.json"
    path.write_text(json.dumps(report(rows({"paper-mean/0": (0, 0), "instruments-mean/0": (3, -2),
                                            "instruments-density/0": (5, 0), "mixed-mean/0": (1, -2),
                                            "mixed-density/0": (5, 0), "paper-density/0": (2, 0)}))))
    decide.main([str(path)])
    decision = json.loads((tmp_path / "decision.json").read_text())
    # both mixtures cost random bins; the pooling is then tested on the paper's sampling alone
    assert not decision["sampling"]["instruments"]["wins"] and not decision["sampling"]["mixed"]["wins"]
    assert decision["chosen"] == "paper-density"


def test_the_measurements_decide_nothing(study, tmp_path):
    """Rows of the real measurements that favour another variant do not change the choice."""
    _, merge = study
    names = ("paper-mean/0", "instruments-mean/0", "instruments-density/0", "paper-density/0", "mixed-mean/0",
             "mixed-density/0")
    tables = rows(dict.fromkeys(names, (0, 0)))
    measured = rows(dict(zip(names, [(0, 0), (5, 5), (9, 9), (9, 9), (5, 5), (9, 9)], strict=True)), group="measured")
    for part, chosen in (("a", tables), ("b", measured)):
        (tmp_path / part).mkdir()
        (tmp_path / part / "compare.json").write_text(json.dumps(report(chosen)))
    assert merge.main([str(tmp_path / "a" / "compare.json"), str(tmp_path / "b" / "compare.json"),
                       "--out", str(tmp_path / "out")]) == 0
    assert json.loads((tmp_path / "out" / "decision.json").read_text())["chosen"] == "paper-mean"
    assert "**tables, encoder only**" in (tmp_path / "out" / "compare.md").read_text()
