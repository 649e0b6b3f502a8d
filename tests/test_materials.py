"""`frenbrdf render` of material files (read by frenbrdf.io.read_material; tests/io/test_formats.py tests the reading)."""

from __future__ import annotations

import matplotlib.image
import numpy as np

from frenbrdf.cli import main
from frenbrdf.data.nbrdf_import import keras_nbrdf
from frenbrdf.io.keras import read_keras_nbrdf
from frenbrdf.render.renderer import Scene, render

from .conftest import PUBLISHED, needs_published, random_layers, write_keras_h5


def test_render_an_h5_without_mitsuba(tmp_path, capsys):
    """`frenbrdf render x.h5` with the metric renderer: the network's own render, as a PNG."""
    h5 = write_keras_h5(tmp_path / "keras.h5", random_layers([6, 8, 3], seed=5))
    out = tmp_path / "keras.png"
    assert main(["render", str(h5), "--out", str(out), "--resolution", "24"]) == 0
    assert "wrote" in capsys.readouterr().out
    written = matplotlib.image.imread(out)[..., :3]
    expected = render(keras_nbrdf(read_keras_nbrdf(h5)), Scene(resolution=24))
    np.testing.assert_allclose(written, expected, atol=1 / 255 + 1e-6)  # 8-bit PNG
    assert expected.max() > 0


@needs_published
def test_render_a_published_h5_without_mitsuba(tmp_path):
    out = tmp_path / "published.png"
    assert main(["render", str(PUBLISHED[0]), "--out", str(out), "--resolution", "32"]) == 0
    image = matplotlib.image.imread(out)[..., :3]
    assert image.shape == (32, 32, 3) and image[16, 16].max() > 0
