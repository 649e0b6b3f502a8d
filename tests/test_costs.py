"""Costs bounded before work starts (issue 45): each size an input declares either runs in bounded memory or is
refused at once, the limit named."""

from __future__ import annotations

import resource
import subprocess
import sys
import tracemalloc

import matplotlib.image
import numpy as np
import pytest

from frenbrdf.models import NBRDF
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.render import renderer
from frenbrdf.render.renderer import Scene, material_mask, render, render_linear, save_png

from .conftest import random_nbrdf_params


def _peak_bytes(function, *args) -> int:
    """The most memory numpy and Python allocated at once while ``function(*args)`` ran (tracemalloc)."""
    tracemalloc.start()
    try:
        function(*args)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


# --- the metric renderer works in tiles --------------------------------------------------------------------------


def test_a_render_in_tiny_tiles_is_the_render_in_one(monkeypatch):
    rng = np.random.default_rng(0)
    table = np.abs(rng.normal(size=(3, 90, 90, 180)))
    nbrdf = NBRDF(random_nbrdf_params(), LogRelativeMapping(np.full(3, 0.1)))
    scene = Scene(resolution=29, environment_samples=16)
    whole = {name: (render_linear(source, scene), render(source, scene)) for name, source in
             (("table", table), ("callable", lambda wi, wo: wi * wo + 0.1), ("nbrdf", nbrdf))}
    mask = material_mask(scene)
    monkeypatch.setattr(renderer, "TILE_PIXELS", 2 * 29 + 5)  # two rows a tile, the last tile one row
    assert len(renderer._tiles(scene)) == 15
    for name, source in (("table", table), ("callable", lambda wi, wo: wi * wo + 0.1)):
        np.testing.assert_array_equal(render_linear(source, scene), whole[name][0])  # every bit
        np.testing.assert_array_equal(render(source, scene), whole[name][1])
    # The network's float32 matrix products round differently by batch size: equal to float32 rounding.
    np.testing.assert_allclose(render_linear(nbrdf, scene), whole["nbrdf"][0], rtol=1e-6, atol=1e-12)
    np.testing.assert_array_equal(material_mask(scene), mask)


def test_a_large_render_shows_its_progress_and_a_small_one_does_not(monkeypatch, capsys):
    # A render of 8192² takes minutes on two cores: the command shows a bar over its bands so that it is not taken
    # for a hung one. Renders of fewer bands than PROGRESS_TILES (training's, evaluation's) stay silent.
    monkeypatch.setattr(renderer, "TILE_PIXELS", 29)  # one row a band: 29 bands
    scene = Scene(resolution=29, environment_samples=16)
    for progress, tiles_for_a_bar, shown in ((True, 29, True), (True, 30, False), (False, 1, False)):
        monkeypatch.setattr(renderer, "PROGRESS_TILES", tiles_for_a_bar)
        render(lambda wi, wo: np.full(wi.shape, 0.2), scene, progress=progress)
        assert ("render: " in capsys.readouterr().err) == shown, (progress, tiles_for_a_bar)


def test_render_memory_is_that_of_a_tile_not_of_the_image(monkeypatch):
    monkeypatch.setattr(renderer, "TILE_PIXELS", 4096)
    scene = Scene(resolution=300)  # above CACHED_RESOLUTION: nothing kept between renders
    image_bytes = 300 * 300 * 3 * 8
    peak = _peak_bytes(render, lambda wi, wo: np.full(wi.shape, 0.2), scene)
    # 4096 pixels × about 8 KB while a tile is built; the whole image's pairs would take some 400 MB.
    assert peak - image_bytes < 60e6, peak / 1e6


def test_save_png_writes_matplotlibs_bytes_in_little_memory(tmp_path):
    rng = np.random.default_rng(1)
    image = rng.uniform(-0.2, 1.2, size=(1024, 1024, 3))
    image[3, 5, 1] = np.nan
    matplotlib.image.imsave(tmp_path / "expected.png", np.clip(image, 0, 1))
    peak = _peak_bytes(save_png, tmp_path / "image.png", image)
    assert (tmp_path / "image.png").read_bytes() == (tmp_path / "expected.png").read_bytes()
    # The RGBA bytes (4 MB) and a band of rows; matplotlib's own conversion of a float image takes 64 MB.
    assert peak < 16e6, peak / 1e6


def test_a_mitsuba_render_above_its_own_limit_is_refused_before_any_work(tmp_path):
    from frenbrdf.render.mitsuba.scene import MAX_MITSUBA_RESOLUTION, render_material

    assert MAX_MITSUBA_RESOLUTION < renderer.MAX_RESOLUTION
    # The material is not even read: a missing file gives the size's error, not the file's.
    with pytest.raises(ValueError, match=f"resolution must be in 1 … {MAX_MITSUBA_RESOLUTION}"):
        render_material(tmp_path / "missing.binary", resolution=MAX_MITSUBA_RESOLUTION + 1, spp=1)


def test_a_mitsuba_render_of_more_samples_than_its_limit_is_refused_before_any_work(tmp_path):
    from frenbrdf.render.mitsuba.scene import MAX_MITSUBA_RESOLUTION, MAX_MITSUBA_SAMPLES, render_material

    spp = MAX_MITSUBA_SAMPLES // MAX_MITSUBA_RESOLUTION**2  # the most at the largest size
    with pytest.raises(ValueError, match=f"spp {spp + 1} at {MAX_MITSUBA_RESOLUTION}² asks for .* e.g. spp {spp} "):
        render_material(tmp_path / "missing.binary", resolution=MAX_MITSUBA_RESOLUTION, spp=spp + 1)
    with pytest.raises(ValueError, match="spp 65536 at 1024²"):  # the CLI's largest spp
        render_material(tmp_path / "missing.binary", resolution=1024, spp=1 << 16)


# --- spectra: lmax bounded by what the variant's fit costs ---------------------------------------------------------


def test_the_measured_fit_refuses_an_lmax_whose_matrix_would_not_fit():
    from frenbrdf.models.losses import MAX_LMAX, MAX_MEASURED_LMAX, FrequencyLossConfig

    FrequencyLossConfig(lmax=MAX_LMAX, fit="sphere")
    FrequencyLossConfig(lmax=MAX_MEASURED_LMAX, fit="measured")
    with pytest.raises(ValueError, match=f"lmax must lie in 1 … {MAX_MEASURED_LMAX} with fit 'measured'"):
        FrequencyLossConfig(lmax=MAX_MEASURED_LMAX + 1, fit="measured")


@pytest.mark.parametrize(("variant", "lmax", "limit"), [("tone", 0, "80"), ("tone", 300, "80"), ("paper", 0, "511"),
                                                        ("paper", 512, "511")])
def test_spectrum_refuses_an_lmax_out_of_range_before_any_work(tmp_path, variant, lmax, limit):
    from frenbrdf.evaluation.spectrum import spectrum_report

    material = tmp_path / "missing.binary"  # not read: the size is refused first
    with pytest.raises(ValueError, match=f"lmax must be a whole number in 1 … {limit} for variant '{variant}', "
                                         f"got {lmax}"):
        spectrum_report([material], tmp_path / "out", variant=variant, lmax=lmax)
    assert not (tmp_path / "out").exists()


def test_spectrum_takes_the_sphere_fits_larger_lmax():
    from frenbrdf.evaluation.spectrum import MAX_SPECTRUM_LMAX, largest_lmax
    from frenbrdf.models.losses import MAX_LMAX

    assert largest_lmax("tone") == largest_lmax("highlights") == MAX_SPECTRUM_LMAX < largest_lmax("paper") == MAX_LMAX


# --- training: a step's memory computed from the config ----------------------------------------------------------


def test_a_training_config_whose_step_would_not_fit_is_refused_naming_the_field_and_its_range():
    from frenbrdf.io.merl import N_BINS
    from frenbrdf.training import config_for
    from frenbrdf.training.config import MAX_STEP_BYTES

    for method in ("frenbrdf", "nbrdf", "hyperbrdf"):  # the presets fit, with room
        cfg = config_for(method)
        context, query, fixed, state = cfg.step_bytes()
        assert state + cfg.batch_materials * (cfg.context_samples * context + cfg.query_samples * query + fixed) \
            < MAX_STEP_BYTES / 4
    with pytest.raises(ValueError, match=r"context_samples in 1 … [\d,]+"):
        config_for("frenbrdf", context_samples=N_BINS)
    with pytest.raises(ValueError, match=r"batch_materials in 1 … \d"):  # L_fre's nodes at lmax 511
        config_for("frenbrdf", loss={"frequency": {"lmax": 511}})
    config_for("nbrdf", loss={"frequency": {"lmax": 511}})  # no L_fre (η = 0): no nodes


def test_the_largest_context_a_message_allows_is_accepted():
    import re

    from frenbrdf.training import config_for

    with pytest.raises(ValueError) as refused:
        config_for("frenbrdf", context_samples=1_000_000)
    largest = int(re.search(r"context_samples in 1 … ([\d,]+)", str(refused.value))[1].replace(",", ""))
    config_for("frenbrdf", context_samples=largest)
    with pytest.raises(ValueError):
        config_for("frenbrdf", context_samples=largest + 1)


# --- samples: the most a file may hold runs in a few GB ----------------------------------------------------------


@pytest.mark.slow
def test_reconstruct_at_the_largest_accepted_sample_count_runs_in_a_few_gb(tmp_path):
    from frenbrdf.io.samples import FORMS, MAX_SAMPLES

    rng = np.random.default_rng(0)

    def directions():
        v = rng.normal(size=(MAX_SAMPLES, 3))
        v[:, 2] = np.abs(v[:, 2]) + 0.05
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    columns = np.concatenate([directions(), directions(), rng.uniform(0.01, 0.5, size=(MAX_SAMPLES, 3))], axis=1)
    np.savez(tmp_path / "samples.npz", **dict(zip(FORMS["vectors"], columns.T, strict=True)))
    del columns
    cap = 6 << 30  # address space: the process's resident peak is about half of it

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    result = subprocess.run([sys.executable, "-m", "frenbrdf.cli", "reconstruct", str(tmp_path / "samples.npz"),
                             "--out", str(tmp_path / "out"), "--refine", "none", "--quiet"], capture_output=True,
                            text=True, timeout=900, preexec_fn=limit)
    assert result.returncode == 0, result.stderr[-2000:]
