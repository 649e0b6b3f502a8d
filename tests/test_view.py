"""``frenbrdf view``: the page, checked in a real browser against the metric renderer and the NBRDF in Python.

The browser tests open the page in headless Chromium (WebGL2 on the CPU through SwiftShader) with URL parameters
that fix the light, exposure and edit position, and compare a screenshot of the sphere with
:func:`frenbrdf.render.render` of the same material and lights. They skip only where no Chromium is installed
(``apt-get install chromium``; ``.ci/run`` installs it).
"""

from __future__ import annotations

import io
import itertools
import json
import math
import re

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf.cli import main
from frenbrdf.io import write_material
from frenbrdf.models.nbrdf import NBRDF
from frenbrdf.render import Scene, material_mask, render
from frenbrdf.render.lighting import KEY_LIGHT
from frenbrdf.render.viewer import view
from frenbrdf.render.viewer.browser import Browser, find_chromium
from frenbrdf.render.viewer.sources import Material, combined, make_edit

#: The PSNR (dB, over the lit sphere) a page must reach against the metric renderer: a correct shader gives
#: about 51–59 dB (8-bit rounding against the renderer's PNG truncation), one with two weights swapped ~20.
PSNR_FLOOR = 40.0
SIZE = 128


@pytest.fixture(scope="module")
def model():
    return frenbrdf.Model.pretrained()


@pytest.fixture(scope="module")
def latents(model):
    rng = np.random.default_rng(3)
    return rng.normal(scale=0.8, size=(2, model.config.encoder.latent))


@pytest.fixture(scope="module")
def material(model, latents) -> NBRDF:
    return model.decode(latents[0])


@pytest.fixture(scope="module")
def browser():
    if find_chromium() is None:
        pytest.skip("no Chromium installed (apt-get install -y chromium; .ci/run installs it): the page is not "
                    "checked in a browser")
    with Browser() as running:
        yield running


def _open(browser, tmp_path, html: str, query: str, name: str = "page.html"):
    path = tmp_path / name
    path.write_text(html, encoding="utf-8")
    page = browser.open(path.as_uri() + query, size=(900, 700))
    state = page.wait("window.frenbrdfView && (window.frenbrdfView.ready || window.frenbrdfView.error) && "
                      "document.body.dataset.state", timeout=120)
    return page, state, path


def _sphere(page) -> np.ndarray:
    from PIL import Image

    box = page.evaluate("(() => { const r = document.getElementById('canvas').getBoundingClientRect(); "
                        "return [r.x, r.y, r.width, r.height]; })()")
    png = page.screenshot(tuple(box))
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64) / 255


def _psnr(image: np.ndarray, reference: np.ndarray, scene: Scene) -> float:
    error = (image - reference)[material_mask(scene)]
    return 10 * math.log10(1 / np.mean(error ** 2))


def _key_scene(theta: float, phi: float, exposure: float) -> Scene:
    """The metric renderer's scene with only the key light, at (θ, φ) degrees as the page's URL gives it."""
    t, p = math.radians(theta), math.radians(phi)
    direction = (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))
    return Scene(resolution=SIZE, light_directions=(direction,), light_colors=(KEY_LIGHT[1],), environment_samples=0,
                 exposure=exposure)


def _swapped(nbrdf: NBRDF) -> NBRDF:
    """The NBRDF with two weights of one unit of its first layer swapped (what a shader reading an input in the wrong
    place computes): the swap that changes the material most (many units are inactive, many swaps do little)."""
    from frenbrdf.render.viewer.sources import nbrdf_samples

    values, (wi, wo) = nbrdf_samples(nbrdf, 300)
    best, chosen = -1.0, None
    for unit in range(nbrdf.params[0].shape[1]):
        for i, j in itertools.combinations(range(6), 2):
            params = [p.clone() for p in nbrdf.params]
            first = params[0][0]
            first[unit, i], first[unit, j] = first[unit, j].clone(), first[unit, i].clone()
            candidate = NBRDF(params, nbrdf.mapping)
            change = float(np.abs(np.log1p(candidate(wi, wo)) - np.log1p(values)).mean())
            if change > best:
                best, chosen = change, candidate
    return chosen


# ---- the page, without a browser ------------------------------------------------------------------------------


def test_page_is_self_contained_and_carries_the_material(material, model):
    page = view(material)
    html = page.html
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", html), "the page must fetch nothing"
    assert "http://" not in html and "https://" not in html
    data = json.loads(re.search(r'id="frenbrdf-data">(.*?)</script>', html, re.S).group(1))
    assert data["format"] == "frenbrdf-view" and data["edit"] is None
    (network,) = data["networks"]
    assert network["widths"] == [6, *model.config.nbrdf.hidden, 3] and not network["ordered"]
    assert "<iframe srcdoc=" in page._repr_html_()  # shown inline in Jupyter
    assert len(html) < 100_000


def test_cli_writes_a_page_and_refuses_bad_input(tmp_path, material, capsys):
    saved = tmp_path / "a.pt"
    write_material(saved, material.weights())
    out = tmp_path / "a.html"
    assert main(["view", str(saved), "--out", str(out), "--quiet"]) == 0
    assert out.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    capsys.readouterr()
    (tmp_path / "notes.txt").write_text("not a material")
    (tmp_path / "folder").mkdir()
    for argv, message in (
            ([str(saved), "--out", str(out)], "exists; pass --overwrite"),
            ([str(saved), "--out", str(tmp_path / "a.png")], "must end in .html"),
            ([str(tmp_path / "missing.pt"), "--out", str(tmp_path / "b.html")], "missing.pt"),
            ([str(tmp_path / "notes.txt"), "--out", str(tmp_path / "b.html")], "unknown format"),
            ([str(tmp_path / "folder"), "--out", str(tmp_path / "b.html")], "not a reconstruct result")):
        with pytest.raises(SystemExit) as exit_:
            main(["view", *argv, "--quiet"])
        assert exit_.value.code == 2
        assert message in capsys.readouterr().err
    assert not (tmp_path / "b.html").exists()


# ---- in the browser -------------------------------------------------------------------------------------------


def test_sphere_matches_the_metric_renderer_and_polar_plot_the_nbrdf(browser, tmp_path, material):
    theta, phi, exposure = 35.0, 120.0, 1.7
    query = f"?light={theta},{phi}&exposure={exposure}&env=0&fill=0&size={SIZE}&theta_i=30"
    page, state, path = _open(browser, tmp_path, view(material).html, query)
    assert state == "ready", page.evaluate("window.frenbrdfView.error")
    scene = _key_scene(theta, phi, exposure)
    assert _psnr(_sphere(page), render(material, scene), scene) > PSNR_FLOOR

    polar = page.evaluate("window.frenbrdfView.polar")
    angles = np.radians(polar["theta_o"])
    wi = np.broadcast_to([math.sin(math.radians(30)), 0.0, math.cos(math.radians(30))], (len(angles), 3))
    wo = np.stack([-np.sin(angles), np.zeros_like(angles), np.cos(angles)], axis=-1)
    np.testing.assert_allclose(polar["rgb"], material(wi, wo), rtol=2e-4, atol=1e-7)

    assert page.console_errors() == []
    assert set(page.requests()) <= {path.as_uri() + query}, "the page requested something beyond itself"


def test_default_view_is_the_metric_renderers_image(browser, tmp_path, material):
    """All lights of Scene(): key, fill, rim and the environment's 48 directions, accumulated over frames."""
    page, state, _ = _open(browser, tmp_path, view(material).html, f"?size={SIZE}&chunk=16")
    assert state == "ready"
    scene = Scene(resolution=SIZE)
    assert _psnr(_sphere(page), render(material, scene), scene) > PSNR_FLOOR
    assert page.console_errors() == []


def test_a_shader_with_two_weights_swapped_fails_the_threshold(browser, tmp_path, material):
    query = f"?light=35,120&exposure=1.7&env=0&fill=0&size={SIZE}"
    page, state, _ = _open(browser, tmp_path, view(_swapped(material)).html, query)
    assert state == "ready"
    scene = _key_scene(35, 120, 1.7)
    assert _psnr(_sphere(page), render(material, scene), scene) < PSNR_FLOOR - 10


def test_edit_halfway_matches_the_python_edit(browser, tmp_path, model, latents):
    decoded = model.decode(latents)
    params = [p[[0]].clone() for p in decoded.params]
    params[-1] += torch.tensor([[0.3, -0.2, 0.1]])  # material a refined beyond its decoding: the kept mode exists
    a = Material(NBRDF(params, model.mapping), "a", "test", latents[0], "pretrained")
    b = Material(decoded[1], "b", "test", latents[1], "pretrained")
    edit = make_edit(a, b)
    assert edit.modes == ("kept", "latent")
    page_html = view(a, b).html
    for mode in edit.modes:
        query = f"?light=20,-60&exposure=1.3&env=0&fill=0&size={SIZE}&t=0.5&edit={mode}"
        page, state, _ = _open(browser, tmp_path, page_html, query, f"edit-{mode}.html")
        assert state == "ready"
        scene = _key_scene(20, -60, 1.3)
        reference = render(combined(edit.terms(0.5, mode), edit.mapping), scene)
        assert _psnr(_sphere(page), reference, scene) > PSNR_FLOOR, mode
        assert page.console_errors() == []
    # The kept edit's ends are the materials themselves, the latent one's the decodings.
    assert edit.terms(0.0, "kept") == [(a.nbrdf, 1.0)] and edit.terms(1.0, "latent") == [(edit.keyframes[-1], 1.0)]


def test_a_damaged_page_says_so_instead_of_a_black_canvas(browser, tmp_path, material):
    html = view(material).html
    damaged = re.sub(r'("data":")([A-Za-z0-9+/=]{40})', r"\1", html, count=1)  # 40 base64 characters lost
    page, state, _ = _open(browser, tmp_path, damaged, "")
    assert state == "error"
    assert "damaged" in page.evaluate("document.getElementById('error').textContent")
    assert page.evaluate("document.getElementById('canvas').hidden")
