"""Evaluation: metrics, the reconstruction and editing tables, figures, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from frenbrdf import cli
from frenbrdf.evaluation import EvaluateConfig, edit_pairs, evaluate_runs, evaluate_seeds, image_metrics
from frenbrdf.render import Scene, material_mask
from frenbrdf.training import train

from .conftest import tiny


def test_image_metrics():
    truth = np.full((32, 32, 3), 0.5)
    same = image_metrics(truth, truth)
    assert same["rmse"] == 0 and same["psnr"] == float("inf") and same["ssim"] == pytest.approx(1.0)
    shifted = image_metrics(truth, truth + 0.1)
    assert shifted["rmse"] == pytest.approx(0.1) and shifted["psnr"] == pytest.approx(20.0)
    assert shifted["ssim"] < 1.0


def test_delta_e_sees_hue_not_noise():
    """ΔE is 0 for identical images, below 1 for a 1 % brightness change, and large when a purple
    comes back beige (the failure the colour issue is about)."""
    mask = np.ones((8, 8), dtype=bool)
    purple = np.broadcast_to([0.55, 0.25, 0.60], (8, 8, 3)).copy()
    beige = np.broadcast_to([0.60, 0.52, 0.45], (8, 8, 3)).copy()
    assert image_metrics(purple, purple, mask)["delta_e"] == 0.0
    assert image_metrics(purple, purple * 1.01, mask)["delta_e"] < 1.0
    assert image_metrics(purple, beige, mask)["delta_e"] > 20.0
    half = mask.copy()
    half[:, 4:] = False  # only the masked pixels count
    mixed = purple.copy()
    mixed[:, 4:] = beige[:, 4:]
    assert image_metrics(purple, mixed, half)["delta_e"] == 0.0


def test_image_metrics_measure_the_material_not_the_background():
    scene = Scene(resolution=32, environment_samples=8)
    mask = material_mask(scene)
    assert 0.6 < mask.mean() < 0.8  # the sphere: π/4 of the frame
    truth = np.full((32, 32, 3), 0.5)
    background_only = truth.copy()
    background_only[~mask] = 0.9
    assert image_metrics(truth, background_only, mask)["psnr"] == float("inf")
    assert image_metrics(truth, background_only)["psnr"] < 20  # what the whole frame said
    on_material = truth.copy()
    on_material[mask] += 0.1
    assert image_metrics(truth, on_material, mask)["psnr"] == pytest.approx(20.0)


def test_edits_use_each_unordered_pair_once_at_interior_weights():
    rng = np.random.default_rng(0)
    pairs = edit_pairs(16, 1000, rng)
    assert len(pairs) == 120 and len({tuple(sorted(p)) for p in pairs}) == 120 and all(a != b for a, b in pairs)
    subset = edit_pairs(16, 40, rng)
    assert len(subset) == 40 and len(set(subset)) == 40
    assert all(0 < t < 1 for t in EvaluateConfig().weights)


@pytest.fixture(scope="module")
def tiny_runs(toy_materials, tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    runs = []
    for method in ("frenbrdf", "nbrdf"):
        result = train(tiny(method, toy_materials, root / method, epochs=2))
        runs.append(result.run_dir)
    return runs


def test_evaluate_writes_tables_and_figures(tiny_runs, tmp_path):
    config = EvaluateConfig(samples=300, edits=12, resolution=32, edit_resolution=16, progress=False)
    report = evaluate_runs(tiny_runs, tmp_path / "eval", config=config)
    assert set(report["summary"]) == {"frenbrdf", "nbrdf"}
    n_test = len(report["test_materials"])
    assert all(len(rows) == n_test for rows in report["reconstruction"].values())
    pairs = min(12 // 3, n_test * (n_test - 1) // 2)  # each unordered pair once, three interior t each
    assert all(len(rows) == 3 * pairs for rows in report["editing"].values())
    for rows in report["reconstruction"].values():
        assert all(np.isfinite(r["rmse"]) and 0 <= r["ssim"] <= 1 and r["lfre"] >= 0 for r in rows)
    # t = 0 and t = 1 reproduce the endpoints' reconstructions: their metrics repeat.
    for name in ("evaluation.md", "evaluation.json", "histograms.png", "renders.png", "interpolation.png"):
        assert (tmp_path / "eval" / name).exists(), name
    table = (tmp_path / "eval" / "evaluation.md").read_text()
    assert "Recon PSNR" in table and "paper: frenbrdf" in table
    assert json.loads((tmp_path / "eval" / "evaluation.json").read_text())["summary"] == report["summary"]


def test_evaluate_refuses_runs_of_different_splits(tiny_runs, toy_materials, tmp_path):
    other = train(tiny("nbrdf", toy_materials, tmp_path / "other", epochs=1, seed=5)).run_dir
    with pytest.raises(ValueError, match="different splits"):
        evaluate_runs([tiny_runs[0], other], tmp_path / "eval", config=EvaluateConfig(progress=False))
    with pytest.raises(FileNotFoundError, match="not a training run folder"):
        evaluate_runs([tmp_path], tmp_path / "eval")


def test_cli_evaluate_and_render(tiny_runs, toy_materials, tmp_path, capsys):
    assert cli.main(["evaluate", *map(str, tiny_runs), "--out", str(tmp_path / "eval"), "--samples", "200",
                     "--edits", "6", "--resolution", "32", "--quick", "--quiet"]) == 0
    assert "Recon RMSE" in capsys.readouterr().out
    material = sorted(toy_materials.glob("*.binary"))[0]
    assert cli.main(["render", str(material), "--out", str(tmp_path / "m.png"), "--resolution", "32"]) == 0
    assert (tmp_path / "m.png").exists()


def test_demo_on_a_data_folder_writes_a_report(toy_materials, tmp_path, monkeypatch):
    from frenbrdf import demo

    monkeypatch.setattr(demo, "DEMO_EVALUATION", EvaluateConfig(samples=500, edits=6, resolution=48,
                                                                 edit_resolution=24, progress=False))
    assert cli.main(["demo", "--out", str(tmp_path / "report"), "--data", str(toy_materials), "--epochs", "1",
                     "--quiet"]) == 0
    readme = (tmp_path / "report" / "README.md").read_text()
    assert "## What was run" in readme and "Recon PSNR" in readme and "| total |" in readme
    for method in ("frenbrdf", "nbrdf", "hyperbrdf"):
        assert (tmp_path / "report" / "runs" / method / "best.pt").exists()
    assert (tmp_path / "report" / "evaluation" / "renders.png").exists()


def test_evaluation_compares_runs_of_several_seeds(toy_materials, tmp_path):
    runs = [str(train(tiny(method, toy_materials, tmp_path / method / f"seed-{seed}", epochs=1, seed=seed)).path)
            for method in ("frenbrdf", "nbrdf") for seed in (0, 1)]
    out = tmp_path / "eval"
    config = EvaluateConfig(samples=200, edits=3, resolution=32, edit_resolution=16, progress=False)
    evaluate_seeds(runs, out, config=config)
    table = (out / "evaluation.md").read_text()
    assert "2 seeds (0, 1)" in table and "nbrdf − frenbrdf (95 % CI)" in table
    report = json.loads((out / "evaluation.json").read_text())
    assert report["comparison"]["seeds"] == [0, 1] and set(report["seeds"]) == {"0", "1"}
    psnr = report["comparison"]["metrics"]["psnr"]
    by_seed = [report["seeds"][s]["summary"]["nbrdf"]["psnr"] - report["seeds"][s]["summary"]["frenbrdf"]["psnr"]
               for s in ("0", "1")]
    assert psnr["differences"]["nbrdf"]["mean"] == pytest.approx(np.mean(by_seed))
    assert (out / "seed-0" / "evaluation.md").exists() and (out / "seed-1" / "renders.png").exists()
