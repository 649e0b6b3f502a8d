"""The chart scripts of benches/: each runs on tiny inputs and writes its PNG, CSV and JSON."""

from __future__ import annotations

import csv
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from frenbrdf.training import train

from .conftest import SCRIPT_FOLDERS, mitsuba_jit, tiny


def load_script(name: str):
    """A script of benches/, research/ or release/ (any of their folders) as a module (none is a package)."""
    (path,) = (path for folder in SCRIPT_FOLDERS for path in folder.glob(f"**/{name}.py"))
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as file:
        return list(csv.DictReader(file))


def test_samples_chart_writes_png_csv_and_json(toy_materials, tmp_path):
    chart = load_script("chart_samples")
    runs = [train(tiny(method, toy_materials, tmp_path / method, epochs=1)).path for method in ("frenbrdf", "nbrdf")]
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
    from frenbrdf.data.synth import METALS, AnalyticMaterial, merl_table

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


def test_features_sheet_draws_one_column_per_kind(tmp_path, capsys):
    chart = load_script("chart_features")
    out = tmp_path / "features.png"
    assert chart.main(["--n", "10", "--per-kind", "1", "--resolution", "16", "--out", str(out)]) == 0
    assert out.stat().st_size > 0 and "wrote" in capsys.readouterr().out


def test_eta_chart_pairs_each_eta_with_eta_zero_of_the_same_seed(tmp_path):
    chart = load_script("chart_eta")
    runs = [{"eta": eta, "seed": seed, "psnr": 25.0 + seed + (0.5 if eta else 0.0), "ssim": 0.9, "rmse": 0.05,
             "delta_e": 3.0, "lfre": 1.0 - eta, "edit_psnr": 24.0 + seed * (1 + eta), "edit_delta_e": 4.0,
             "ratio_first": eta * 10, "ratio_last": eta * 5}
            for eta in (0.0, 0.05) for seed in (0, 1, 2)]
    rows = chart.summarise(runs, [0.0, 0.05], [0, 1, 2])
    assert rows[1]["psnr_vs_0"] == pytest.approx(0.5) and rows[0]["psnr_vs_0"] == 0
    assert rows[1]["psnr_sd"] == pytest.approx(1.0)  # seeds differ by 1 dB; the pairing removes it
    assert rows[1]["psnr_vs_0_significant"] and not rows[1]["edit_psnr_vs_0_significant"]
    table = chart.markdown(rows)
    assert "**+0.50 [+0.50, +0.50]**" in table and "+0.05 [" in table  # significant in bold, editing not
    chart.draw(rows, tmp_path / "chart6.png", "test")
    assert (tmp_path / "chart6.png").stat().st_size > 10_000


def test_curves_chart_compares_selection_rules_and_regularisers_paired_by_seed(tmp_path):
    chart = load_script("chart_curves")

    def run(seed, psnr, by_psnr=0.0):
        curve = {"epoch": [1, 2, 3, 4], "seconds": [1.0, 2.0, 3.0, 4.0], "train_rec": [0.5, 0.4, 0.3, 0.2],
                 "val_rec": [0.6, 0.5, 0.5, 0.55], "render_epoch": [2, 4], "render_seconds": [2.0, 4.0],
                 "val_psnr": [20.0 + seed, 21.0 + seed], "val_delta_e": [5.0, 4.0],
                 "best_epoch": {"validation loss": 2, "validation render PSNR": 4}}
        test = {rule: {"psnr": psnr + seed + (by_psnr if rule == "validation render PSNR" else 0.0),
                       "delta_e": 3.0} for rule in chart.RULES}
        return {"curves": curve, "test": test, "ood": {"psnr": psnr - 5 + seed, "delta_e": 6.0}}

    runs = {"frenbrdf": {s: run(s, 30.0, by_psnr=0.4) for s in range(3)},
            "nbrdf": {s: run(s, 29.0, by_psnr=0.2) for s in range(3)},
            "frenbrdf, weight decay 0.1": {s: run(s, 31.0) for s in range(3)}}
    selection = {row["rule"]: row for row in chart.selection_rows(runs)}
    assert selection["validation loss"]["psnr_vs_loss"] == 0
    assert selection["validation render PSNR"]["psnr_vs_loss"] == pytest.approx(0.3)  # over both methods' 6 runs
    assert selection["validation render PSNR"]["psnr_vs_loss_significant"]
    table = chart.regulariser_markdown(runs, {"epochs": 4, "data": "merl", "seeds": [0, 1, 2], "ood": "bank",
                                              "ood_materials": 40})
    weight_decay = next(line for line in table.splitlines() if line.startswith("| frenbrdf, weight decay"))
    assert "**+1.00 [+1.00, +1.00]**" in weight_decay  # +1 dB on every seed, in and out of distribution
    chart.draw(runs, tmp_path / "chart7.png", "test")
    assert (tmp_path / "chart7.png").stat().st_size > 10_000


def test_lfre_floor_evaluates_the_exact_brdf_where_the_loss_evaluates_a_prediction(tmp_path):
    import types

    import torch

    from frenbrdf.data.nbrdf_import import keras_nbrdf
    from frenbrdf.io.keras import read_keras_nbrdf
    from frenbrdf.models.losses import FrequencyLossConfig
    from frenbrdf.models.mapping import LogRelativeMapping
    from frenbrdf.render.scoring import FrequencyMetric

    from .conftest import write_keras_h5

    chart = load_script("lfre_floor")
    rng = np.random.default_rng(0)
    # Outputs x > 0 everywhere, so the clamp of exp(x) − 1 at 0 never acts and log(1 + f) gives x back.
    layers = [(rng.normal(0, 0.3, (6, 8)), np.full(8, 0.5)), (rng.normal(0, 0.3, (8, 3)), np.full(3, 2.0))]
    path = write_keras_h5(tmp_path / "toy.h5", layers)
    metric = FrequencyMetric(FrequencyLossConfig(lmax=11, slices=(0, 45)))
    model = types.SimpleNamespace(mapping=LogRelativeMapping(np.zeros(3), epsilon=1.0))  # log(1 + f)
    exact = chart.exact_coefficients(metric, model, path)
    with torch.no_grad():
        predicted = metric.loss.predicted_coefficients(keras_nbrdf(read_keras_nbrdf(path)).params)[0].numpy()
    np.testing.assert_allclose(exact, predicted, rtol=1e-4, atol=1e-4)
    degrees = metric.loss.sht.plan(torch.float64).degrees_orders()[:, 0]
    shares = chart.shares(exact ** 2, degrees)
    assert sum(shares["bands"].values()) == pytest.approx(1) and sum(shares["slices"]) == pytest.approx(1)


def _variant_run(variant, eta, seed, psnr, highlight, edit=25.0):
    sets = {name: {"psnr": psnr + seed, "delta_e": 3.0, "highlight_psnr": highlight + seed, "highlight_delta_e": 6.0,
                   "lfre": 0.5, "edit_psnr": edit + seed, "edit_delta_e": 4.0, "edit_highlight_psnr": 20.0}
            for name in ("id", "ood")}
    return {"variant": variant, "eta": eta, "seed": seed, "ratio_first": eta * 10, "ratio_last": eta, "sets": sets}


def test_frequency_variants_chart_pairs_each_variant_with_eta_zero_and_names_the_goal(tmp_path):
    chart = load_script("chart_frequency_variants")
    assert [s["id"] for s in chart.plan(["paper", "tone"], [0.0, 0.05], [0, 1])] == [
        "eta-0/seed-0", "eta-0/seed-1", "paper/eta-0.05/seed-0", "paper/eta-0.05/seed-1", "tone/eta-0.05/seed-0",
        "tone/eta-0.05/seed-1"]
    seeds = (0, 1, 2)
    runs = [_variant_run("paper", 0.0, s, 30.0, 20.0) for s in seeds]
    runs += [_variant_run("paper", 0.05, s, 30.0, 20.0 + 0.1 * s) for s in seeds]  # within noise
    runs += [_variant_run("tone", 0.05, s, 30.0, 21.0) for s in seeds]  # +1 dB on the highlights on every seed
    rows = chart.summarise(runs, ["paper", "tone"], [0.0, 0.05], seeds)
    assert [r["variant"] for r in rows] == ["η = 0 (no L_fre)", "paper", "tone"]
    assert rows[2]["id_highlight_psnr_vs_0"] == pytest.approx(1.0) and rows[2]["id_highlight_psnr_vs_0_significant"]
    assert not rows[1]["id_highlight_psnr_vs_0_significant"]
    assert chart.goal(rows) == ["tone η=0.05"]
    table = chart.markdown(rows)
    assert "**+1.00 [+1.00, +1.00]**" in table and "in distr.: highlight PSNR" in table
    chart.draw(rows, tmp_path / "chart9.png", "test")
    assert (tmp_path / "chart9.png").stat().st_size > 10_000


@pytest.mark.slow
def test_frequency_variants_sweep_trains_in_parallel_resumes_and_reports(toy_materials, tmp_path):
    """The three phases at tiny scale: train (2 processes), then report (measures, then the table); a second
    train finds every run finished."""
    import shutil

    import frenbrdf

    chart = load_script("chart_frequency_variants")
    ood = tmp_path / "ood"
    ood.mkdir()
    for i, path in enumerate(sorted(toy_materials.glob("*.binary"))[:3]):
        shutil.copy(path, ood / f"other-{i}.binary")
    overrides = {"epochs": 1, "batch_materials": 2, "context_samples": 256, "query_samples": 512,
                 "augment": {"mix": 0.0, "gain": 0.0, "procedural": 0.0, "preset": "paper"},
                 "model": {"nbrdf": {"hidden": [16, 16]}, "encoder": {"hidden": [32, 32], "latent": 8},
                           "decoder": {"hidden": [32]}}, "loss": {"frequency": {"lmax": 11}}}
    common = ["--data", str(toy_materials), "--work", str(tmp_path / "work"), "--variants", "paper", "tone",
              "--etas", "0", "0.05", "--seeds", "0", "1", "--overrides", json.dumps(overrides), "--threads", "1",
              "--ood", str(ood), "--resolution", "16", "--edits", "6"]
    assert chart.main(["train", *common, "--jobs", "2"]) == 0
    runs = sorted(p.relative_to(tmp_path / "work" / "runs").as_posix() for p in (tmp_path / "work").rglob("last.pt"))
    assert len(runs) == 6 and "tone/eta-0.05/seed-1/last.pt" in runs
    assert frenbrdf.training.Run(tmp_path / "work" / "runs" / "tone" / "eta-0.05" / "seed-0").config.loss.frequency \
        .variant == "tone"
    assert chart.main(["report", *common, "--out", str(tmp_path / "charts"), "--name", "variants"]) == 0
    saved = json.loads((tmp_path / "charts" / "variants.json").read_text())
    assert [r["variant"] for r in saved["rows"]] == ["η = 0 (no L_fre)", "paper", "tone"]
    assert all(np.isfinite(r["sets"]["ood"]["highlight_psnr"]) and r["sets"]["ood"]["materials"] == 3
               for r in saved["runs"])
    assert {"id_highlight_psnr_vs_0", "ood_edit_psnr_vs_0"} <= set(saved["rows"][1])
    before = (tmp_path / "work" / "measured").stat().st_mtime_ns
    assert chart.main(["train", *common]) == 0  # every run finished: nothing to do
    assert (tmp_path / "work" / "measured").stat().st_mtime_ns == before
    # The report from the measurements alone (brought back from the machine that trained), elsewhere.
    shutil.copytree(tmp_path / "work" / "measured", tmp_path / "elsewhere" / "measured")
    elsewhere = [a if a != str(tmp_path / "work") else str(tmp_path / "elsewhere") for a in common[2:]]
    assert chart.main(["report", *elsewhere, "--out", str(tmp_path / "charts2"), "--name", "variants"]) == 0
    again = json.loads((tmp_path / "charts2" / "variants.json").read_text())
    assert again["rows"] == saved["rows"]
    # `all` on a work folder whose runs are all measured trains nothing and reports.
    assert chart.main(["all", *common, "--out", str(tmp_path / "charts3"), "--name", "variants"]) == 0
    assert json.loads((tmp_path / "charts3" / "variants.json").read_text())["rows"] == saved["rows"]
