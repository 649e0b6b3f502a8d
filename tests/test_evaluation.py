"""Evaluation: metrics, the reconstruction and editing tables, figures, the CLI."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from frenbrdf import cli
from frenbrdf.data.synth import write_bank
from frenbrdf.evaluation.evaluate import (
    ROWS,
    EvaluateConfig,
    edit_pairs,
    evaluate_runs,
    evaluate_seeds,
    evaluation_set,
    image_metrics,
)
from frenbrdf.render.figures import rendered_materials
from frenbrdf.render.renderer import Scene, material_mask
from frenbrdf.training import Run, train

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


def test_the_highlight_metric_sees_a_blurred_highlight_that_the_whole_material_psnr_hardly_sees():
    """A prediction equal to the truth except in its highlight: the highlight PSNR falls far more than the PSNR."""
    from frenbrdf.io.merl import SHAPE
    from frenbrdf.render.renderer import render_linear, tonemap
    from frenbrdf.render.scoring import HIGHLIGHT_FRACTION, highlight_mask

    scene = Scene(resolution=64, environment_samples=8)
    mask = material_mask(scene)
    rng = np.random.default_rng(0)
    linear = render_linear(np.broadcast_to(rng.uniform(0.05, 0.2, (3, 1, 1, 1)), SHAPE).copy(), scene)
    highlight = highlight_mask(linear, mask)
    assert highlight.sum() == pytest.approx(HIGHLIGHT_FRACTION * mask.sum(), abs=3) and not (highlight & ~mask).any()
    luminance = linear @ [0.2126, 0.7152, 0.0722]
    assert luminance[highlight].min() >= luminance[mask & ~highlight].max()  # the brightest pixels, by the linear truth
    truth = tonemap(linear)
    dimmed = truth.copy()
    dimmed[highlight] *= 0.8  # the highlight comes back dimmer, nothing else changes
    metrics = image_metrics(truth, dimmed, mask, highlight)
    assert metrics["psnr"] - metrics["highlight_psnr"] > 10  # 1/20 of the pixels: 13 dB apart
    assert metrics["highlight_delta_e"] > 5 * metrics["delta_e"]
    assert "highlight_psnr" not in image_metrics(truth, dimmed, mask)
    with pytest.raises(ValueError, match="highlight mask"):
        image_metrics(truth, dimmed, mask, np.zeros_like(mask))


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
        runs.append(result.path)
    return runs


def test_edit_pairs_are_those_of_the_listed_combinations_without_listing_them():
    import itertools

    for n, most in [(2, 1), (5, 3), (9, 20), (40, 7), (200, 50), (9, 100), (6, 0)]:
        listed = list(itertools.combinations(range(n), 2))
        if len(listed) > most:
            listed = [listed[i] for i in sorted(np.random.default_rng(n).choice(len(listed), size=most, replace=False))]
        assert edit_pairs(n, most, np.random.default_rng(n)) == listed


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
    for name in ("evaluation.md", "evaluation.json", "histograms.png", "renders.png", "interpolation.png",
                 "spectrum.png"):
        assert (tmp_path / "eval" / name).exists(), name
    table = (tmp_path / "eval" / "evaluation.md").read_text()
    assert "Recon PSNR" in table and "paper: frenbrdf" in table
    assert "Recon highlight PSNR" in table and "Edit highlight PSNR" in table
    assert all(np.isfinite(summary["highlight_psnr"]) for summary in report["summary"].values())
    assert json.loads((tmp_path / "eval" / "evaluation.json").read_text())["summary"] == report["summary"]
    assert "Evaluation set: the runs' test split, read from" in table


@pytest.mark.parametrize("name", ["renders.png", "histograms.png", "interpolation.png", "spectrum.png"])
def test_a_users_file_under_a_figures_name_is_refused_before_any_work(tiny_runs, tmp_path, monkeypatch, name):
    from frenbrdf.evaluation import evaluate as evaluation

    out = tmp_path / "eval"
    out.mkdir()
    (out / name).write_text("mine")
    monkeypatch.setattr(evaluation, "_reconstruct_all", lambda *a, **k: pytest.fail("work began"))
    with pytest.raises(ValueError, match=f"holds {name}, which this command would replace"):
        evaluate_runs(tiny_runs, out, config=EvaluateConfig(progress=False), overwrite=True)
    assert (out / name).read_text() == "mine"


def test_without_data_the_runs_own_data_folder_is_an_input_never_written(tiny_runs):
    data = Run(tiny_runs[0]).data
    before = sorted(p.name for p in data.iterdir())
    with pytest.raises(ValueError, match="is the input"):
        evaluate_runs(tiny_runs, data, config=EvaluateConfig(progress=False), overwrite=True)
    assert sorted(p.name for p in data.iterdir()) == before


def test_every_table_reports_colour_difference(tiny_runs, tmp_path):
    config = EvaluateConfig(samples=300, edits=6, resolution=32, edit_resolution=16, progress=False)
    report = evaluate_runs(tiny_runs, tmp_path / "eval", config=config)
    table = (tmp_path / "eval" / "evaluation.md").read_text()
    # The rows of the Markdown table: ours, then "–" for each of the paper's columns (the paper has no ΔE).
    ours = " | ".join(f"{summary['delta_e']:.3g}" for summary in report["summary"].values())
    assert f"| Recon ΔE ↓ | {ours} | – | – | – |" in table and "| Edit ΔE ↓ |" in table
    for method, summary in report["summary"].items():
        rows = report["reconstruction"][method]
        assert summary["delta_e"] == pytest.approx(np.mean([r["delta_e"] for r in rows]))
        assert summary["edit_delta_e"] == pytest.approx(np.mean([r["delta_e"] for r in report["editing"][method]]))
        # Where colour is lost: the worst material first, with its ΔE and PSNR, and the count above 5.
        worst = max(rows, key=lambda r: r["delta_e"])
        above = sum(r["delta_e"] > 5 for r in rows)
        assert (f"| {method} | {above} of {len(rows)} | {worst['material']} ({worst['delta_e']:.1f}, "
                f"{worst['psnr']:.1f} dB)") in table
    saved = json.loads((tmp_path / "eval" / "evaluation.json").read_text())
    assert {"delta_e", "edit_delta_e"} <= set(saved["summary"]["frenbrdf"]) and "colour" in saved
    assert "`renders.png` shows the first" in table


REFINED_KEYS = {"refined_psnr", "refined_lfre", "refined_delta_e", "edit_refined_psnr", "edit_refined_delta_e"}


def test_refined_rows_appear_only_when_refinement_runs(tiny_runs, tmp_path):
    config = EvaluateConfig(samples=300, edits=6, resolution=32, edit_resolution=16, progress=False)
    plain = evaluate_runs(tiny_runs, tmp_path / "plain", config=config)
    assert all(not REFINED_KEYS & set(summary) for summary in plain["summary"].values())
    assert "refinement" not in plain and "refined" not in (tmp_path / "plain" / "evaluation.md").read_text()

    refined = evaluate_runs(tiny_runs, tmp_path / "refined", config=dataclasses.replace(config, refine="latent"))
    table = (tmp_path / "refined" / "evaluation.md").read_text()
    for method, summary in refined["summary"].items():
        assert REFINED_KEYS <= set(summary) and all(np.isfinite(summary[key]) for key in REFINED_KEYS)
        # The encoder-only numbers are the same with or without refinement: the same bins, the same pairs.
        assert {key: summary[key] for key in plain["summary"][method]} == pytest.approx(plain["summary"][method])
        rows = refined["reconstruction"][method]
        assert summary["refined_psnr"] == pytest.approx(np.mean([r["refined_psnr"] for r in rows]))
        assert all(r["refine_seconds"] > 0 and 0 <= r["refined_ssim"] <= 1 for r in rows)
        assert refined["refinement"]["seconds_per_material"][method] == pytest.approx(
            np.mean([r["refine_seconds"] for r in rows]))
    assert refined["refinement"]["budget"] == "latent"
    for label in ("Recon PSNR, refined z ↑", "Recon ΔE, refined z ↓", "Recon L_fre, refined z ↓",
                  "Edit PSNR, refined z ↑", "Edit ΔE, refined z ↓"):
        assert f"| {label} |" in table, label
    assert "**Encoder only**" in table and "`frenbrdf reconstruct --refine latent`" in table
    assert "s of refinement per material" in table and "its refined one (`<method> refined`)" in table


def test_refined_rows_are_what_reconstruct_gives_on_the_same_bins(tiny_runs, tmp_path):
    """Each refined row is :func:`frenbrdf.models.reconstruct.reconstruct` run on the bins the encoder was given."""
    from frenbrdf.io.merl import N_BINS, read_merl
    from frenbrdf.io.sampling import bin_directions, sample_bins
    from frenbrdf.models.reconstruct import BUDGETS, reconstruct
    from frenbrdf.render.renderer import render_linear, tonemap

    config = EvaluateConfig(samples=250, edits=3, resolution=32, edit_resolution=16, progress=False, seed=3,
                            refine="full")
    report = evaluate_runs(tiny_runs, tmp_path / "eval", config=config)
    model = Run(tiny_runs[0]).model()
    rng = np.random.default_rng(config.seed)  # bins are drawn per material, in name order, from the seed
    scene = Scene(resolution=config.resolution)
    for name, row in zip(report["test_materials"], report["reconstruction"][model.method], strict=True):
        table = read_merl(Path(report["data"]) / f"{name}.binary")
        bins = sample_bins(table, rng, config.samples)
        result = reconstruct(model, table.reshape(3, N_BINS)[:, bins].T, bin_directions(bins),
                             refine=dataclasses.replace(BUDGETS["full"], seed=config.seed))
        expected = image_metrics(tonemap(render_linear(table, scene)), tonemap(render_linear(result.nbrdf, scene)),
                                 material_mask(scene))
        assert row["material"] == name
        assert row["refined_psnr"] == pytest.approx(expected["psnr"], abs=1e-3)
        assert row["refined_delta_e"] == pytest.approx(expected["delta_e"], abs=1e-3)
        assert row["refined_psnr"] != pytest.approx(row["psnr"], abs=1e-3)  # refinement changed the material
    assert "Recon PSNR, refined z + weights ↑" in (tmp_path / "eval" / "evaluation.md").read_text()


def test_frequency_metric_measures_a_latent_and_an_nbrdf_alike(tiny_runs, toy_materials):
    """A refined NBRDF is no decoder output; L_fre of the NBRDF decoded from z is L_fre of z."""
    from frenbrdf.io.merl import read_merl
    from frenbrdf.render.scoring import FrequencyMetric

    model = Run(tiny_runs[0]).model()
    table = read_merl(sorted(toy_materials.glob("*.binary"))[0])
    metric = FrequencyMetric()
    z = np.linspace(-1, 1, model.config.encoder.latent)
    assert metric(model, table, model.decode(z)) == pytest.approx(metric(model, table, z), rel=1e-6)
    assert metric(model, table, model.decode(-z)) != pytest.approx(metric(model, table, z), rel=1e-3)


def test_a_bad_refinement_budget_is_a_clear_error(tiny_runs, tmp_path, capsys):
    with pytest.raises(ValueError, match="refine must be a refinement budget, one of .*'latent'.*got 'lots'"):
        EvaluateConfig(refine="lots")
    with pytest.raises(SystemExit):
        cli.main(["evaluate", *map(str, tiny_runs), "--out", str(tmp_path / "eval"), "--refine", "lots"])
    assert "--refine: invalid choice: 'lots'" in capsys.readouterr().err


def test_the_render_grid_shows_the_first_materials_and_the_worst_colours():
    names = [f"m{i}" for i in range(10)]
    delta_e = {"m0": 50, "m1": 1, "m2": 1, "m3": 1, "m4": 2, "m5": 9, "m6": 3, "m7": 30, "m8": 8, "m9": 0}
    per_material = {"a": [{"material": n, "delta_e": delta_e[n]} for n in names],
                    "b": [{"material": n, "delta_e": delta_e[n] + (20 if n == "m4" else 0)} for n in names]}
    first, hardest = rendered_materials(names, per_material)
    assert first == ["m0", "m1", "m2", "m3"]
    assert hardest == ["m7", "m4", "m5", "m8"]  # by mean ΔE over the methods; m0 is shown once, among the first
    assert rendered_materials(names[:5], per_material) == (names[:4], ["m4"])


def test_an_evaluation_keeps_the_renders_of_the_materials_it_can_show_and_no_others():
    from frenbrdf.render.figures import drop_unshown_renders

    names = [f"m{i}" for i in range(40)]
    rng = np.random.default_rng(0)
    per_material, renders, mean_delta_e = {"a": [], "b": []}, {}, {}
    for name in names:  # as the reconstruction pass goes, material by material
        for rows in per_material.values():
            rows.append({"material": name, "delta_e": float(rng.integers(0, 12))})  # ties: the first found stays
        renders[name] = {"truth": np.zeros(1)}
        mean_delta_e[name] = float(np.mean([rows[-1]["delta_e"] for rows in per_material.values()]))
        drop_unshown_renders(renders, names, mean_delta_e)
        assert len(renders) <= 8
    first, hardest = rendered_materials(names, per_material)
    assert set(renders) == set(first + hardest)


def test_evaluate_refuses_runs_of_different_splits(tiny_runs, toy_materials, tmp_path):
    other = train(tiny("nbrdf", toy_materials, tmp_path / "other", epochs=1, seed=5)).path
    with pytest.raises(ValueError, match="different splits"):
        evaluate_runs([tiny_runs[0], other], tmp_path / "eval", config=EvaluateConfig(progress=False))
    with pytest.raises(FileNotFoundError, match="not a training run folder"):
        evaluate_runs([tmp_path], tmp_path / "eval")


def test_evaluate_gives_each_sampling_pattern_its_own_rows(tiny_runs, tmp_path, capsys):
    """``--patterns``: each material encoded from each pattern's pairs; the first pattern's numbers (and editing,
    which uses its latents) are those of an evaluation of it alone."""
    plain = evaluate_runs(tiny_runs, tmp_path / "plain", config=EvaluateConfig(
        samples=200, edits=3, resolution=32, edit_resolution=96, progress=False))
    assert "drawn by the sampling pattern `merl-bins`" in (tmp_path / "plain" / "evaluation.md").read_text()
    assert cli.main(["evaluate", *map(str, tiny_runs), "--out", str(tmp_path / "two"), "--samples", "200",
                     "--edits", "3", "--resolution", "32", "--quick", "--quiet",
                     "--patterns", "merl-bins", "image-based"]) == 0
    table = capsys.readouterr().out
    report = json.loads((tmp_path / "two" / "evaluation.json").read_text())
    assert report["config"]["patterns"] == ["merl-bins", "image-based"]
    for method, summary in report["summary"].items():
        assert {key: summary[key] for key in plain["summary"][method]} == pytest.approx(plain["summary"][method])
        rows = report["reconstruction"][method]
        assert summary["psnr@image-based"] == pytest.approx(np.mean([r["psnr@image-based"] for r in rows]))
        assert summary["rmse_x100@image-based"] == pytest.approx(100 * np.mean([r["rmse@image-based"] for r in rows]))
        assert summary["psnr@image-based"] != summary["psnr"]
        assert not any(key.startswith("edit_") and "@" in key for key in summary)  # editing: the first pattern's
        psnr = " | ".join(f"{s['psnr@image-based']:.3g}" for s in report["summary"].values())
        assert f"| image-based: Recon PSNR ↑ | {psnr} | – | – | – |" in table
    assert "| merl-bins: Recon PSNR ↑ |" in table and "| Edit PSNR ↑ |" in table
    assert "samples of each sampling pattern: `merl-bins`, `image-based`" in table
    for patterns in (("uniform", "uniform"), ("nope",), ()):
        with pytest.raises(ValueError, match="patterns must be one or more distinct sampling patterns"):
            EvaluateConfig(patterns=patterns)


def test_cli_evaluate_and_render(tiny_runs, toy_materials, tmp_path, capsys):
    assert cli.main(["evaluate", *map(str, tiny_runs), "--out", str(tmp_path / "eval"), "--samples", "200",
                     "--edits", "6", "--resolution", "32", "--quick", "--quiet"]) == 0
    assert "Recon RMSE" in capsys.readouterr().out
    assert cli.main(["evaluate", *map(str, tiny_runs), "--out", str(tmp_path / "refined"), "--samples", "200",
                     "--edits", "3", "--resolution", "32", "--quick", "--quiet", "--refine", "latent"]) == 0
    assert "| Recon PSNR, refined z ↑ |" in capsys.readouterr().out
    assert json.loads((tmp_path / "refined" / "evaluation.json").read_text())["config"]["refine"] == "latent"
    material = sorted(toy_materials.glob("*.binary"))[0]
    assert cli.main(["render", str(material), "--out", str(tmp_path / "m.png"), "--resolution", "32"]) == 0
    assert (tmp_path / "m.png").exists()


def test_demo_on_a_data_folder_writes_a_report(toy_materials, tmp_path, monkeypatch):
    from frenbrdf import demo

    assert demo.DEMO_EVALUATION.refine == "latent"  # the demo reports what a user gets, beside the paper's protocol
    monkeypatch.setattr(demo, "DEMO_EVALUATION", EvaluateConfig(samples=500, edits=6, resolution=48,
                                                                 edit_resolution=24, progress=False, refine="latent"))
    assert cli.main(["demo", "--out", str(tmp_path / "report"), "--data", str(toy_materials), "--epochs", "1",
                     "--quiet"]) == 0
    readme = (tmp_path / "report" / "README.md").read_text()
    assert "## What was run" in readme and "Recon PSNR" in readme and "| total |" in readme
    assert "Recon ΔE" in readme and "highest ΔE" in readme
    assert "| Recon ΔE, refined z ↓ |" in readme and "**Encoder only**" in readme and "--refine latent" in readme
    for method in ("frenbrdf", "nbrdf", "hyperbrdf"):
        assert (tmp_path / "report" / "runs" / method / "best.pt").exists()
    assert (tmp_path / "report" / "evaluation" / "renders.png").exists()


@pytest.fixture(scope="module")
def seed_runs(toy_materials, tmp_path_factory):
    root = tmp_path_factory.mktemp("seed-runs")
    return [str(train(tiny(method, toy_materials, root / method / f"seed-{seed}", epochs=1, seed=seed)).path)
            for method in ("frenbrdf", "nbrdf") for seed in (0, 1)]


@pytest.fixture(scope="module")
def other_bank(tmp_path_factory):
    """Materials the runs never saw: a second, tiny synthetic bank."""
    folder = tmp_path_factory.mktemp("other-bank")
    write_bank(folder, n=3, seed=11, progress=False)
    return folder


def test_evaluation_compares_runs_of_several_seeds(seed_runs, tmp_path):
    runs = seed_runs
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
    assert "| Recon ΔE ↓ |" in table and "| Edit ΔE ↓ |" in table and "highest ΔE" in table
    assert set(report["comparison"]["metrics"]) == {key for key, _ in ROWS}
    assert "refined" not in table


def test_the_seeds_table_carries_the_refined_rows(seed_runs, tmp_path):
    config = EvaluateConfig(samples=200, edits=3, resolution=32, edit_resolution=16, progress=False, refine="latent")
    report = evaluate_seeds(seed_runs, tmp_path / "eval", config=config)
    metrics = report["comparison"]["metrics"]
    assert REFINED_KEYS <= set(metrics)
    by_seed = [report["seeds"][s]["summary"]["nbrdf"]["refined_psnr"] for s in ("0", "1")]
    assert metrics["refined_psnr"]["methods"]["nbrdf"]["by_seed"] == pytest.approx(by_seed)
    table = (tmp_path / "eval" / "evaluation.md").read_text()
    assert "| Recon PSNR, refined z ↑ |" in table and "| Edit ΔE, refined z ↓ |" in table
    assert "**Encoder only**" in table


def test_all_evaluates_every_material_of_another_folder(tiny_runs, other_bank, tmp_path):
    config = EvaluateConfig(samples=200, edits=3, resolution=32, edit_resolution=16, progress=False,
                            all_materials=True)
    report = evaluate_runs(tiny_runs, tmp_path / "eval", data=str(other_bank), config=config)
    bank = sorted(path.stem for path in other_bank.glob("*.binary"))
    assert report["test_materials"] == bank
    assert all([r["material"] for r in rows] == bank for rows in report["reconstruction"].values())
    assert {r["a"] for rows in report["editing"].values() for r in rows} <= set(bank)  # edits among them
    evaluated = report["evaluation_set"]
    assert evaluated["out_of_distribution"] and evaluated["excluded"] == [] and evaluated["materials"] == 3
    assert evaluated["trained_on"] == [str(Run(tiny_runs[0]).data)]
    table = (tmp_path / "eval" / "evaluation.md").read_text()
    assert f"all 3 materials of {other_bank} that no run saw (out-of-distribution)" in table
    assert "Reconstruction on 3 materials" in table
    assert f"No material of `{other_bank}` was left out" in table


def test_all_on_the_training_folder_leaves_out_what_the_runs_saw(tiny_runs, toy_materials):
    runs = [Run(path) for path in tiny_runs]
    evaluated = evaluation_set(runs, toy_materials, all_materials=True)
    seen = set(runs[0].split.train) | set(runs[0].split.val)
    assert evaluated.excluded == sorted(seen) and evaluated.names == sorted(runs[0].split.test)
    assert evaluation_set(runs, toy_materials, all_materials=True, max_materials=1).names == evaluated.names[:1]
    assert "the first 1 (by name) of the 2" in evaluation_set(runs, toy_materials, all_materials=True,
                                                              max_materials=1).describe()


def test_all_over_seeds_evaluates_every_seed_on_the_same_materials(seed_runs, other_bank, toy_materials, tmp_path):
    config = EvaluateConfig(samples=200, edits=3, resolution=32, edit_resolution=16, progress=False,
                            all_materials=True, max_materials=2)
    report = evaluate_seeds(seed_runs, tmp_path / "eval", data=str(other_bank), config=config)
    first_two = sorted(path.stem for path in other_bank.glob("*.binary"))[:2]
    assert [r["test_materials"] for r in report["seeds"].values()] == [first_two, first_two]
    assert report["evaluation_set"]["out_of_distribution"] and report["comparison"]["seeds"] == [0, 1]
    table = (tmp_path / "eval" / "evaluation.md").read_text()
    assert "the same 2 materials for every seed" in table and "out-of-distribution" in table
    # On the training folder: only what no seed trained or validated on, the same for both seeds.
    runs = [Run(path) for path in seed_runs]
    seen = {name for run in runs for name in (*run.split.train, *run.split.val)}
    unseen = sorted({path.stem for path in toy_materials.glob("*.binary")} - seen)
    assert len(unseen) == 1, "seeds 0 and 1 leave one toy material unseen"
    on_training = evaluate_seeds(seed_runs, tmp_path / "eval-train", data=str(toy_materials),
                                 config=dataclasses.replace(config, max_materials=0))
    assert [r["test_materials"] for r in on_training["seeds"].values()] == [unseen, unseen]
    assert on_training["evaluation_set"]["excluded"] == sorted(seen)
    assert f"Left out {len(seen)} materials of `{toy_materials}` that a run trained or validated on: " \
           f"{', '.join(sorted(seen))}." in (tmp_path / "eval-train" / "evaluation.md").read_text()
    # One material has no pair to edit: the editing rows cannot be compared, and the table says so.
    assert "edit_psnr" not in on_training["comparison"]["metrics"] and "delta_e" in on_training["comparison"]["metrics"]
    assert "Left out, not finite on every seed: Edit PSNR ↑" in (tmp_path / "eval-train" / "evaluation.md").read_text()
    for seed in (0, 1):  # each seed's own table: no rows of NaN
        text = (tmp_path / "eval-train" / f"seed-{seed}" / "evaluation.md").read_text()
        assert "no editing rows (editing interpolates two" in text and "Edit PSNR" not in text and "nan" not in text


def test_all_errors_are_clear(tiny_runs, toy_materials, tmp_path, capsys):
    base = ["evaluate", *map(str, tiny_runs), "--out", str(tmp_path / "eval"), "--quiet", "--all"]
    for extra, message in (([], "needs that folder: give it with --data DIR"),
                           (["--data", str(tmp_path / "nowhere")], "does not exist"),
                           (["--data", str(tmp_path)], "holds no material files"),
                           (["--data", str(tmp_path), "--max-materials", "-1"], "--max-materials: expected")):
        with pytest.raises(SystemExit):
            cli.main(base + extra)
        assert message in capsys.readouterr().err, extra
    assert not (tmp_path / "eval" / "evaluation.json").exists()
    runs = [Run(path) for path in tiny_runs]
    seen_only = tmp_path / "seen-only"
    seen_only.mkdir()
    for name in runs[0].split.train:
        (seen_only / f"{name}.binary").symlink_to(toy_materials / f"{name}.binary")
    with pytest.raises(ValueError, match=f"all {len(runs[0].split.train)} materials of .* none is left to evaluate"):
        evaluation_set(runs, seen_only, all_materials=True)


def test_cli_evaluate_all(tiny_runs, other_bank, tmp_path, capsys):
    assert cli.main(["evaluate", *map(str, tiny_runs), "--out", str(tmp_path / "eval"), "--data", str(other_bank),
                     "--all", "--max-materials", "2", "--samples", "200", "--edits", "3", "--resolution", "32",
                     "--quick", "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "out-of-distribution" in printed and "Recon ΔE" in printed
    assert len(json.loads((tmp_path / "eval" / "evaluation.json").read_text())["test_materials"]) == 2


def test_a_method_evaluated_twice_is_named_alike_in_every_seed(tmp_path):
    """Two runs of one method (e.g. trained with and without augmentation) keep one name across seeds,
    so the over-seeds comparison pairs them: the folder above the method's for ``--seeds`` runs."""
    from frenbrdf.evaluation.evaluate import run_label

    assert {run_label(tmp_path / "bank-paper" / "frenbrdf" / f"seed-{s}", "frenbrdf") for s in (0, 1, 2)} == {
        "bank-paper"}
    assert {run_label(tmp_path / "sweep" / f"eta-{eta}" / "seed-0", "frenbrdf") for eta in (0.05, 0.5)} == {
        "eta-0.05", "eta-0.5"}  # a sweep's variants, each its own folder of seeds
    assert run_label(tmp_path / "runs" / "frenbrdf-paper") == "frenbrdf-paper"


def test_an_edit_at_its_ends_is_the_reconstruction_of_that_material(tiny_runs, toy_materials):
    from frenbrdf.io.merl import read_merl
    from frenbrdf.render.renderer import render_linear
    from frenbrdf.render.scoring import edit_metrics, reconstruction_rows

    model = Run(tiny_runs[0]).model()
    files = sorted(toy_materials.glob("*.binary"))[:2]
    latents: dict = {}
    rows = reconstruction_rows(model, files, samples=300, resolution=24, frequency_metric=False, progress=False,
                               latents=latents)
    assert list(latents) == [f.stem for f in files]
    scene = Scene(resolution=24)
    a, b = (render_linear(read_merl(f), scene) for f in files)
    z_a, z_b = latents[files[0].stem], latents[files[1].stem]
    for t, row in ((0.0, rows[0]), (1.0, rows[1])):
        assert edit_metrics(model, z_a, z_b, a, b, t, scene, material_mask(scene))["psnr"] == pytest.approx(row["psnr"])
    middle = edit_metrics(model, z_a, z_b, a, b, 0.5, scene, material_mask(scene))
    assert middle["psnr"] != pytest.approx(rows[0]["psnr"]) and np.isfinite(middle["psnr"])


def test_reconstruction_rows_read_materials_through_a_sampling_pattern(tiny_runs, toy_materials):
    """``pattern`` encodes each material from that device's pairs; the default is the random bins as before."""
    from frenbrdf.io import read_material
    from frenbrdf.io.sampling import as_table, sample_bins, truth_samples
    from frenbrdf.render.scoring import reconstruction_rows

    model = Run(tiny_runs[0]).model()
    files = sorted(toy_materials.glob("*.binary"))[:2]
    latents: dict[str, dict] = {"merl-bins": {}, "in-plane": {}}
    for pattern, found in latents.items():
        reconstruction_rows(model, files, samples=300, resolution=16, frequency_metric=False, progress=False,
                            latents=found, pattern=pattern)
    rng = np.random.default_rng(0)  # the random bins drawn as they always were
    for path in files:
        table = as_table(read_material(path))
        drawn = truth_samples(table, sample_bins(table, rng, 300), rng)
        assert np.allclose(latents["merl-bins"][path.stem], model.encode(*drawn))
        assert not np.allclose(latents["in-plane"][path.stem], latents["merl-bins"][path.stem])
