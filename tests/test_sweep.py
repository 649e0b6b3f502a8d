"""Sweeps and ``frenbrdf select``: the Pareto front, choosing from a measured front, training candidates."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from frenbrdf import cli
from frenbrdf.evaluation.select import select_config
from frenbrdf.evaluation.variants import MeasureSettings, Variant, capacity_variants
from frenbrdf.models.losses import FrequencyLossConfig
from frenbrdf.training import load_config

from .conftest import script_module, tiny

sweeps = script_module("sweeps")
combine_seeds, frequency_variants, pareto_front, save_chart, spread_slices = (
    sweeps.combine_seeds, sweeps.frequency_variants, sweeps.pareto_front, sweeps.save_chart, sweeps.spread_slices)


def _row(name, hidden, latent, psnr, **extra):
    weights = sum(a * b + b for a, b in zip((6, *hidden), (*hidden, 3), strict=True))
    return {"name": name, "axis": "hidden", "value": list(hidden), "hidden": list(hidden), "latent": latent,
            "nbrdf_weights": weights, "bytes_per_material": 4 * weights, "latent_bytes": 4 * latent, "psnr": psnr,
            "psnr_std": 1.0, "val_materials": 10, "ssim": 0.9, "rmse": 0.05, "lfre": 1e-3,
            "throughput_qps": 1e9 / weights,
            "config": {"method": "frenbrdf", "epochs": 3, "model": {"nbrdf": {"hidden": list(hidden)},
                                                                    "encoder": {"latent": latent}}}, **extra}


@pytest.fixture()
def data_dir(tmp_path):
    """A folder that passes as data where nothing is trained (select reads the front, not the files)."""
    folder = tmp_path / "data"
    folder.mkdir()
    (folder / "placeholder.binary").write_bytes(b"")
    return folder


@pytest.fixture()
def front_file(tmp_path):
    rows = [_row("hidden=60x60x60x60", (60, 60, 60, 60), 40, 27.0), _row("hidden=21x21", (21, 21), 40, 24.0),
            _row("default", (32, 32), 40, 26.0), _row("latent=16", (32, 32), 16, 25.0),
            _row("hidden=48x48", (48, 48), 40, 25.5)]
    paths = save_chart("capacity", rows, tmp_path / "charts", {"data": "somewhere", "epochs": 3})
    return paths["json"]


def test_variants_vary_one_setting_around_the_default():
    assert spread_slices(4) == (0, 24, 48, 72) and spread_slices(2) == (0, 48) and len(spread_slices(8)) == 8
    for n in (15, 16, 17, 45, 89, 90):  # every count gives distinct valid θ_h bins (16 and up failed before)
        slices = spread_slices(n)
        assert len(set(slices)) == n and min(slices) == 0 and max(slices) <= 89, n
        FrequencyLossConfig(slices=slices)
    names = [v.name for v in frequency_variants()]
    assert names[0] == "default" and len(names) == len(set(names)) == 9
    sizes = [v.config(tiny("frenbrdf", Path("d"), Path("o"))).model.nbrdf.n_weights
             for v in capacity_variants()[1:5]]
    assert sizes[0] == 675 and sizes[-1] == 11583


def test_pareto_front_marks_the_non_dominated_rows():
    rows = [_row("a", (21, 21), 40, 24.0), _row("b", (32, 32), 40, 23.0), _row("c", (32, 32), 40, 26.0),
            _row("d", (32, 32), 16, 25.0)]
    assert pareto_front(rows) == [True, False, True, True]


def test_seeds_combine_into_one_row_per_variant_paired_with_the_default():
    runs = [_row("default", (32, 32), 40, 22.0, seed=0), _row("default", (32, 32), 40, 23.0, seed=1),
            _row("small", (21, 21), 40, 21.5, seed=0), _row("small", (21, 21), 40, 23.1, seed=1)]
    runs[0]["axis"] = runs[1]["axis"] = "default"
    default, small = combine_seeds(runs)
    assert default["seeds"] == [0, 1] and default["psnr"] == pytest.approx(22.5) and default["psnr_delta"] == 0
    assert small["psnr_delta_by_seed"] == pytest.approx([-0.5, 0.1]) and small["psnr_delta"] == pytest.approx(-0.2)
    assert small["psnr_delta_spread"] == pytest.approx(0.6) and small["psnr_by_seed"] == [21.5, 23.1]


def test_charts_are_written_with_csv_and_json(front_file):
    chart = json.loads(front_file.read_text())
    assert chart["chart"] == "capacity" and sum(r["front"] for r in chart["rows"]) >= 2
    assert front_file.with_suffix(".png").stat().st_size > 0
    csv_lines = front_file.with_suffix(".csv").read_text().splitlines()
    assert csv_lines[0].startswith("name,axis,value") and len(csv_lines) == 6


def test_select_from_a_front_picks_the_smallest_reaching_the_target(front_file, data_dir, tmp_path):
    selection = select_config(data_dir, 25.2, tmp_path / "sel", front=front_file, progress=False)
    # By bytes: 21x21 (24.0) < 32x32 z16 (25.0) < 32x32 z40 (26.0): the default is the first to reach 25.2.
    assert selection.reached and selection.chosen["name"] == "default"
    assert [r["name"] for r in selection.considered][:3] == ["hidden=21x21", "latent=16", "default"]
    config = load_config(selection.config_path)
    assert config.model.nbrdf.hidden == (32, 32) and config.data == str(data_dir)
    assert "Chosen: **default**" in (tmp_path / "sel" / "selection.md").read_text()
    assert select_config(data_dir, 20, tmp_path / "low", front=front_file, progress=False).chosen["name"] \
        == "hidden=21x21"


def test_select_refuses_an_impossible_target_clearly(front_file, data_dir, tmp_path, capsys):
    selection = select_config(data_dir, 40, tmp_path / "sel", front=front_file, progress=False)
    assert not selection.reached and selection.config_path is None and selection.best["psnr"] == 27.0
    assert not (tmp_path / "sel" / "config.json").exists()
    assert "No configuration reaches 40 dB" in selection.report_path.read_text()
    code = cli.main(["select", "--data", str(data_dir), "--target-psnr", "40", "--out", str(tmp_path / "c"),
                     "--front", str(front_file), "--quiet"])
    assert code == 1
    assert "no configuration reaches 40 dB" in capsys.readouterr().err and "27.00 dB" in \
        (tmp_path / "c" / "selection.md").read_text()


def test_select_trains_candidates_smallest_first_and_writes_a_loadable_config(toy_materials, tmp_path):
    data = tmp_path / "four"  # the fewest materials a split takes: the run reads little
    data.mkdir()
    for path in sorted(toy_materials.glob("*.binary"))[:4]:
        (data / path.name).symlink_to(path)
    # η = 0 (the "nbrdf" preset) spares the true SH coefficients; select's path is the same for any method.
    base = tiny("nbrdf", data, tmp_path / "unused", epochs=1)
    variants = [Variant("big", "hidden", [24, 24], {"model": {"nbrdf": {"hidden": [24, 24]}}}),
                Variant("small", "hidden", [8, 8], {"model": {"nbrdf": {"hidden": [8, 8]}}})]
    measure = MeasureSettings(samples=200, resolution=16, lfre=False, progress=False)
    selection = select_config(data, 1.0, tmp_path / "sel", base=base, variants=variants, measure=measure,
                              progress=False)
    assert selection.reached and selection.chosen["name"] == "small" and len(selection.considered) == 1
    chosen = selection.chosen  # a mean ΔE wherever there is a mean PSNR
    rows = chosen["per_material"]
    assert chosen["delta_e"] == pytest.approx(sum(r["delta_e"] for r in rows) / len(rows)) and chosen["delta_e"] > 0
    assert selection.summary["chosen"]["delta_e"] == chosen["delta_e"]
    config = load_config(selection.config_path)
    assert config.model.nbrdf.hidden == (8, 8) and config.model.encoder.latent == 8 and config.epochs == 1
    assert config.out == str(tmp_path / "sel" / "run")
    # Asked again, the measured run is reused, not retrained.
    run = next((tmp_path / "sel" / "runs").iterdir())
    stamp = (run / "best.pt").stat().st_mtime_ns
    again = select_config(data, 1.0, tmp_path / "sel", base=base, variants=variants, measure=measure,
                          progress=False)
    assert again.chosen["psnr"] == selection.chosen["psnr"] and (run / "best.pt").stat().st_mtime_ns == stamp


@pytest.mark.parametrize("argv, message", [
    (["--target-psnr", "nan"], "a finite number of dB > 0"),
    (["--target-psnr", "-3"], "a finite number of dB > 0"),
    (["--target-psnr", "inf"], "a finite number of dB > 0"),
    (["--target-psnr", "30", "--front", "{tmp}/absent.json"], "does not exist"),
    (["--target-psnr", "30", "--front", "{tmp}/bad.json"], "not a capacity front"),
    (["--target-psnr", "30", "--front", "{tmp}/bad.json", "--epochs", "3"], "nothing is trained"),
])
def test_cli_select_rejects_bad_input(argv, message, data_dir, tmp_path, capsys):
    (tmp_path / "bad.json").write_text(json.dumps({"chart": "frequency", "rows": []}))
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["select", "--data", str(data_dir), "--out", str(tmp_path / "sel"), "--quiet", *argv])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_cli_select_rejects_a_missing_data_folder(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["select", "--data", str(tmp_path / "absent"), "--target-psnr", "30", "--out", str(tmp_path / "o")])
    assert exit_info.value.code == 2 and "does not exist" in capsys.readouterr().err


def test_sweeps_time_a_variants_step_on_a_small_folder_and_reuse_the_time(toy_materials, tmp_path, monkeypatch):
    """Chart 2's step time (benches/step_timing.py, from research/charts/sweeps.py): with and without L_fre, on a
    folder of the first few materials; a sweep started again reads it back from the run's folder."""
    from frenbrdf.configs import to_dict

    work = tmp_path / "work"
    cfg = tiny("frenbrdf", toy_materials, work / "runs" / "default-abc")
    Path(cfg.out).mkdir(parents=True)
    config = to_dict(cfg)
    row = {"name": "default", "key": "abc", "run": cfg.out, "config": config}
    timing = sweeps.TimingSettings(steps=2, materials=4)
    assert sweeps.add_step_time(row, work, timing) is row
    assert row["step_ms"] > 0 and row["step_without_fre_ms"] > 0 and row["fre_share"] > -1  # not NaN: L_fre is on
    assert row["timing_threads"] >= 1
    assert len(list((work / "timing-data").glob("*.binary"))) == 4

    def untimed(*args, **kwargs):
        raise AssertionError("timed again")

    monkeypatch.setattr(sweeps, "time_training_step", untimed)
    again = sweeps.add_step_time({"name": "default", "key": "abc", "run": cfg.out, "config": config}, work, timing)
    assert {k: again[k] for k in sweeps.STEP_KEYS} == {k: row[k] for k in sweeps.STEP_KEYS}
