"""``frenbrdf spectrum``: per-degree power spectra of materials and of reconstructions against their truth."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import torch

from frenbrdf import cli
from frenbrdf.data import analytic
from frenbrdf.evaluation.spectrum import SpectrumAnalyser, relative_error_by_band
from frenbrdf.io import write_material
from frenbrdf.io.merl import write_merl
from frenbrdf.io.outputs import MARKER
from frenbrdf.models import NBRDF, NBRDFConfig
from frenbrdf.models.losses import SPHERE_AREA, frequency_variant
from frenbrdf.models.mapping import LogRelativeMapping

PLASTIC = analytic.AnalyticMaterial("plastic", diffuse=(0.3, 0.2, 0.1), specular=0.04, roughness=0.2)


@pytest.mark.parametrize("variant", ["no-floor", "tone"])
def test_a_table_and_the_same_brdf_evaluated_at_the_nodes_have_the_same_spectrum(variant):
    """Where only the measured nodes count; under the paper's sphere fit the nodes below the horizon differ (the
    BRDF is 0 there, the table's extension is not): L_fre's floor."""
    analyser = SpectrumAnalyser(frequency_variant(variant, lmax=15))
    table = analyser.coefficients(analytic.merl_table(PLASTIC))
    exact = analyser.coefficients(lambda wi, wo: analytic.evaluate(PLASTIC, wi, wo))
    assert np.linalg.norm(exact - table) / np.linalg.norm(table) < 0.1
    power = analyser.power(table)
    assert power.shape == (4, 3, 16) and np.allclose(power.sum(-1), (table ** 2).sum(-1) / SPHERE_AREA)
    error = relative_error_by_band(analyser.power(exact - table), power)
    assert set(error) == {"l 0", "l 1–4", "l 5–15"} and all(0 <= v < 0.1 for v in error.values())
    paper = SpectrumAnalyser(frequency_variant("paper", lmax=15))
    floor = paper.coefficients(analytic.merl_table(PLASTIC)) - paper.coefficients(
        lambda wi, wo: analytic.evaluate(PLASTIC, wi, wo))
    assert np.linalg.norm(floor) > 5 * np.linalg.norm(exact - table)


def test_the_spectrum_command_writes_plot_csv_and_json_of_materials_and_of_errors(tmp_path, capsys):
    inputs = tmp_path / "inputs"
    inputs.mkdir()
    write_merl(inputs / "plastic.binary", analytic.merl_table(PLASTIC))
    generator = torch.Generator().manual_seed(0)
    params = [torch.randn(1, *shape, generator=generator) * 0.3 for shape in NBRDFConfig((8, 8)).shapes()]
    write_material(inputs / "guess.pt", NBRDF(params, LogRelativeMapping(np.full(3, 0.05))).weights())
    out = tmp_path / "spectrum"
    argv = ["spectrum", str(inputs / "guess.pt"), "--truth", str(inputs / "plastic.binary"), "--out", str(out),
            "--lmax", "11"]
    assert cli.main(argv) == 0
    assert "guess vs truth: error / truth power" in capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "spectrum.csv", "spectrum.json", "spectrum.png"]
    with open(out / "spectrum.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    assert len(rows) == 3 * 4 * 3 * 12  # truth, guess and guess's error; 4 slices × 3 channels × 12 degrees
    assert {r["spectrum"] for r in rows} == {"material", "error"}
    report = json.loads((out / "spectrum.json").read_text())
    assert list(report["materials"]) == ["plastic (truth)", "guess"] and list(report["errors"]) == ["guess"]
    assert report["errors"]["guess"]["relative_error_by_band"]["l 0"] > 0
    assert cli.main(argv) == 0  # an earlier spectrum folder is replaced
    with pytest.raises(SystemExit):
        cli.main(["spectrum", str(inputs / "plastic.binary"), "--out", str(inputs)])  # never the input's folder
    assert "its folder, or holds it" in capsys.readouterr().err
