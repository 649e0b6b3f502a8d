"""The deterministic metric renderer."""

from __future__ import annotations

import numpy as np
import pytest

from frenbrdf.models import NBRDF
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.render.renderer import Scene, environment_radiance, render, render_linear, save_png, tonemap

from .conftest import constant_table, random_nbrdf_params

SMALL = Scene(resolution=24, environment_samples=16)


def test_constant_brdf_matches_a_direct_sum_over_lights():
    c = 0.3
    image = render_linear(constant_table(c), SMALL)
    # Pixel (row, col) → normal; radiance = c · Σ_l L_l max(0, n·l) (the environment by its fixed samples).
    n = SMALL.resolution
    lights = np.asarray(SMALL.light_directions, dtype=float)
    lights /= np.linalg.norm(lights, axis=1, keepdims=True)
    colours = np.asarray(SMALL.light_colors, dtype=float)
    i = np.arange(SMALL.environment_samples) + 0.5
    z = 1 - 2 * i / SMALL.environment_samples
    phi = np.pi * (1 + 5**0.5) * i
    env = np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], -1)
    lights = np.concatenate([lights, env])
    colours = np.concatenate([colours, environment_radiance(env) * 4 * np.pi / len(env)])
    for row, col in [(12, 12), (3, 12), (12, 20), (18, 7)]:
        x, y = (col + 0.5) / n * 2 - 1, -((row + 0.5) / n * 2 - 1)
        normal = np.array([x, y, np.sqrt(1 - x * x - y * y)])
        expected = c * (colours * np.clip(lights @ normal, 0, None)[:, None]).sum(axis=0)
        np.testing.assert_allclose(image[row, col], expected, rtol=1e-9)
    assert np.all(image[0, 0] == 0)  # background


def test_rendering_is_linear_in_the_brdf():
    rng = np.random.default_rng(0)
    a = np.abs(rng.normal(size=(3, 90, 90, 180)))
    b = np.abs(rng.normal(size=(3, 90, 90, 180)))
    blend = render_linear(0.3 * a + 0.7 * b, SMALL)
    np.testing.assert_allclose(blend, 0.3 * render_linear(a, SMALL) + 0.7 * render_linear(b, SMALL), rtol=1e-10)


def test_nbrdf_render_equals_rendering_its_callable():
    nbrdf = NBRDF([p for p in random_nbrdf_params()], LogRelativeMapping(np.full(3, 0.1)))
    np.testing.assert_allclose(render_linear(nbrdf, SMALL), render_linear(lambda wi, wo: nbrdf(wi, wo), SMALL),
                               rtol=1e-6)


def test_display_image_and_errors(tmp_path):
    image = render(constant_table(0.2), SMALL)
    assert image.shape == (24, 24, 3) and image.min() >= 0 and image.max() <= 1
    np.testing.assert_array_equal(tonemap(np.array([-1.0, 0.5, 4.0])), [0.0, 0.5 ** (1 / 2.2), 1.0])
    with pytest.raises(ValueError, match="shape"):
        render(np.zeros((3, 90, 90)), SMALL)
    with pytest.raises(ValueError, match="NaN"):
        render(lambda wi, wo: np.full(wi.shape, np.nan), SMALL)
    with pytest.raises(ValueError, match="resolution"):
        Scene(resolution=2)
    save_png(tmp_path / "sphere.png", image)
    import matplotlib.image

    assert matplotlib.image.imread(tmp_path / "sphere.png").shape[:2] == (24, 24)
    assert not list(tmp_path.glob(".*"))
