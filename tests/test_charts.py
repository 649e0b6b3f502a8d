"""The chart scripts of benches/: each runs on tiny inputs and writes its PNG, CSV and JSON."""

from __future__ import annotations

import csv
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from frenbrdf.training import train

from .conftest import BENCHES, mitsuba_jit, tiny


def load_script(name: str):
    """A script of benches/ as a module (benches/ is not a package)."""
    spec = importlib.util.spec_from_file_location(name, BENCHES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as file:
        return list(csv.DictReader(file))


def test_samples_chart_writes_png_csv_and_json(toy_materials, tmp_path):
    chart = load_script("chart_samples")
    runs = [train(tiny(method, toy_materials, tmp_path / method, epochs=1)).run_dir for method in ("frenbrdf", "nbrdf")]
    report = chart.samples_chart(runs, tmp_path / "charts", counts=(20, None), seeds=2, resolution=16,
                                 max_materials=1, name="samples", progress=False)
    rows = read_csv(tmp_path / "charts" / "samples.csv")
    assert [(r["method"], r["samples"], r["draws"]) for r in rows] == [
        ("frenbrdf", "20", "2"), ("frenbrdf", "all", "1"), ("nbrdf", "20", "2"), ("nbrdf", "all", "1")]
    assert all(np.isfinite(float(r["psnr_mean"])) and 0 < float(r["ssim_mean"]) <= 1 for r in rows)
    assert float(rows[1]["psnr_std"]) == 0 and float(rows[1]["n_samples"]) > 1e6  # every measured bin, one draw
    saved = json.loads((tmp_path / "charts" / "samples.json").read_text())
    assert saved["summary"] == report["summary"] and len(saved["per_material"]) == 2 * (2 + 1)
    assert (tmp_path / "charts" / "samples.png").stat().st_size > 0
    assert sorted(p.name for p in (tmp_path / "charts").iterdir()) == ["samples.csv", "samples.json", "samples.png"]


def test_rendering_chart_writes_png_csv_and_json(tmp_path):
    mitsuba_jit()
    from frenbrdf.synth import METALS, AnalyticMaterial, merl_table

    chart = load_script("chart_rendering")
    n, k = METALS["gold"]
    gold = merl_table(AnalyticMaterial("gold", metal_n=n, metal_k=k, roughness=0.1))
    chart.rendering_chart({"gold": gold}, tmp_path, spps=(1, 4), reference_spp=16, resolution=16, repeats=1,
                          name="rendering")
    rows = read_csv(tmp_path / "rendering.csv")
    assert [(r["sampling"], r["spp"]) for r in rows] == [("fitted", "1"), ("fitted", "4"), ("cosine", "1"),
                                                        ("cosine", "4")]
    assert all(float(r["display_rmse"]) > 0 and float(r["seconds"]) > 0 for r in rows)
    saved = json.loads((tmp_path / "rendering.json").read_text())
    assert saved["rows"][0]["display_rmse"] == pytest.approx(float(rows[0]["display_rmse"]))
    assert saved["materials"]["gold"]["sampling"]["lobes"]  # a metal: fitted GGX lobes
    assert (tmp_path / "rendering.png").stat().st_size > 0


def test_eta_chart_pairs_each_eta_with_eta_zero_of_the_same_seed(tmp_path):
    chart = load_script("chart_eta")
    runs = [{"eta": eta, "seed": seed, "psnr": 25.0 + seed + (0.5 if eta else 0.0), "ssim": 0.9, "rmse": 0.05,
             "lfre": 1.0 - eta, "ratio_first": eta * 10, "ratio_last": eta * 5}
            for eta in (0.0, 0.05) for seed in (0, 1, 2)]
    rows = chart.summarise(runs, [0.0, 0.05], [0, 1, 2])
    assert rows[1]["psnr_vs_0"] == pytest.approx(0.5) and rows[0]["psnr_vs_0"] == 0
    assert rows[1]["psnr_sd"] == pytest.approx(1.0)  # seeds differ by 1 dB; the pairing removes it
    chart.draw(rows, tmp_path / "chart6.png", "test")
    assert (tmp_path / "chart6.png").stat().st_size > 10_000
