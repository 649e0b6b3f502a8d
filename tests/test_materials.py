"""One loader for material files (frenbrdf.data.materials), and `frenbrdf render` of every format."""

from __future__ import annotations

import matplotlib.image
import numpy as np
import pytest

import frenbrdf
from frenbrdf.cli import main
from frenbrdf.data.fitting import save_nbrdf
from frenbrdf.data.materials import load_material_file
from frenbrdf.data.nbrdf_import import keras_nbrdf, load_keras_nbrdf
from frenbrdf.models import NBRDF
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.render.renderer import Scene, render

from .conftest import PUBLISHED, constant_table, needs_published, random_layers, random_nbrdf_params, write_keras_h5


def test_each_format_loads_as_a_table_or_an_nbrdf(tmp_path):
    table = constant_table(0.2)
    frenbrdf.write_merl(tmp_path / "grey.binary", table)
    np.testing.assert_array_equal(load_material_file(tmp_path / "grey.binary"),
                                  frenbrdf.read_merl(tmp_path / "grey.binary"))

    nbrdf = NBRDF(random_nbrdf_params(), LogRelativeMapping(np.full(3, 0.1)))
    save_nbrdf(tmp_path / "fit.pt", nbrdf)
    (tmp_path / "fit.weights").write_bytes((tmp_path / "fit.pt").read_bytes())  # other names: by content
    for name in ("fit.pt", "fit.weights"):
        loaded = load_material_file(tmp_path / name)
        assert isinstance(loaded, NBRDF)
        assert all(np.array_equal(a.numpy(), b.numpy()) for a, b in zip(loaded.params, nbrdf.params))

    layers = random_layers([6, 8, 3], seed=4)
    h5 = write_keras_h5(tmp_path / "keras.h5", layers)
    from_h5 = load_material_file(h5)
    assert isinstance(from_h5, NBRDF) and len(from_h5) == 1
    wi = np.array([[0.3, 0.1, 0.9]]) / np.linalg.norm([0.3, 0.1, 0.9])
    wo = np.array([[-0.2, 0.4, 0.8]]) / np.linalg.norm([-0.2, 0.4, 0.8])
    np.testing.assert_allclose(from_h5(wi, wo), keras_nbrdf(load_keras_nbrdf(h5))(wi, wo), rtol=1e-12)


def test_bad_files_give_clear_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.binary"):
        load_material_file(tmp_path / "missing.binary")
    (tmp_path / "junk.bin").write_bytes(b"not a material")
    with pytest.raises(ValueError, match="neither a MERL file"):
        load_material_file(tmp_path / "junk.bin")
    (tmp_path / "short.binary").write_bytes(b"\0" * 12)
    with pytest.raises(ValueError, match="short.binary"):
        load_material_file(tmp_path / "short.binary")


def test_render_an_h5_without_mitsuba(tmp_path, capsys):
    """`frenbrdf render x.h5` with the metric renderer: the network's own render, as a PNG."""
    h5 = write_keras_h5(tmp_path / "keras.h5", random_layers([6, 8, 3], seed=5))
    out = tmp_path / "keras.png"
    assert main(["render", str(h5), "--out", str(out), "--resolution", "24"]) == 0
    assert "wrote" in capsys.readouterr().out
    written = matplotlib.image.imread(out)[..., :3]
    expected = render(keras_nbrdf(load_keras_nbrdf(h5)), Scene(resolution=24))
    np.testing.assert_allclose(written, expected, atol=1 / 255 + 1e-6)  # 8-bit PNG
    assert expected.max() > 0


@needs_published
def test_render_a_published_h5_without_mitsuba(tmp_path):
    out = tmp_path / "published.png"
    assert main(["render", str(PUBLISHED[0]), "--out", str(out), "--resolution", "32"]) == 0
    image = matplotlib.image.imread(out)[..., :3]
    assert image.shape == (32, 32, 3) and image[16, 16].max() > 0
