"""Shared fixtures: synthetic MERL tables and the published data beside the checkout."""

from __future__ import annotations

import importlib
import importlib.util
import itertools
import os
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

from frenbrdf.data.folders import list_materials, split_materials
from frenbrdf.training import prepare

# CI runs the same examples every time, so a red run is reproducible; locally each run
# explores new ones.
settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

SHARED_DATA = Path(os.environ.get("FRENBRDF_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))
#: The published NBRDF fits (Keras .h5) of 80 MERL materials, when ../shared is beside the checkout.
PUBLISHED_DIR = SHARED_DATA / "merl-nbrdf"
PUBLISHED = sorted(PUBLISHED_DIR.glob("*.h5"))
needs_published = pytest.mark.skipif(
    not PUBLISHED, reason=f"published NBRDF weights not found in {PUBLISHED_DIR} (set FRENBRDF_SHARED_DATA)")
#: The folders of scripts outside the package: benchmarks, research (studies, charts) and the release step.
SCRIPT_FOLDERS = [Path(__file__).resolve().parents[1] / name for name in ("benches", "research", "release")]


def _installed(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):  # ValueError: blocked in sys.modules
        return False


HAVE_MITSUBA = _installed("mitsuba") and _installed("drjit")


def mitsuba_jit():
    """Mitsuba with the plugin registered in its JIT variant ``llvm_ad_rgb``, for the tests that need it.

    Skips (with the reason) where Mitsuba or the packaged LLVM is not installed; fails where the
    packaged LLVM is installed and the variant still does not work, so a broken install is never a skip.
    """
    if not HAVE_MITSUBA:
        pytest.skip("mitsuba is not installed (pip install mitsuba)")
    from frenbrdf.render import mitsuba as fm

    if fm.register() == fm.FALLBACK_VARIANT:
        if fm.packaged_libllvm() is None:
            pytest.skip(f"llvm_ad_rgb is not usable here and {fm.LLVM_PACKAGE} is not installed "
                        "(pip install -e '.[test]' installs it on Linux x86-64, or apt-get install -y libllvm19)")
        pytest.fail(f"llvm_ad_rgb is not usable although {fm.LLVM_PACKAGE} is installed "
                    f"({fm.LIBLLVM_VARIABLE}={os.environ.get(fm.LIBLLVM_VARIABLE)!r})")
    import mitsuba

    return mitsuba


def script_module(name: str):
    """A script's module from benches/, research/ or release/ (not part of the installed package), imported as the
    scripts import each other: their folders on ``sys.path``."""
    for folder in (folder for top in SCRIPT_FOLDERS for folder in (top, *sorted(top.iterdir())) if folder.is_dir()):
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))
    return importlib.import_module(name)


@pytest.fixture(scope="session")
def merl_table() -> np.ndarray:
    """A smooth random table in reflectance units, with MERL-style missing bins.

    The values are `stored × scale` products of random stored values, as a table read
    from any MERL file would be.
    """
    rng = np.random.default_rng(1234)
    stored = rng.lognormal(mean=2.0, sigma=2.0, size=(3, 90, 90, 180))
    stored[:, :, 80:, :] = -1.0  # a block of missing measurements, marked as MERL does
    scales = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])
    return stored * scales[:, None, None, None]


@pytest.fixture()
def merl_file(tmp_path, merl_table) -> Path:
    import frenbrdf

    path = tmp_path / "material.binary"
    frenbrdf.write_merl(path, merl_table)
    return path


def unit_vectors(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def toy_table(rng: np.random.Generator) -> np.ndarray:
    """A Lambert + normalised Blinn–Phong material at the MERL bins, missing bins marked."""
    import frenbrdf
    from frenbrdf.io.merl import CHANNEL_SCALES

    grid = frenbrdf.merl_bin_grid()
    diffuse, specular, exponent = rng.uniform(0.05, 0.8, 3), rng.uniform(0.05, 1.0), rng.uniform(10, 300)
    lobe = specular * (exponent + 2) / (2 * np.pi) * np.cos(grid[..., 0]) ** exponent
    table = np.stack([diffuse[c] / np.pi + lobe for c in range(3)])
    missing = ~frenbrdf.merl_above_horizon()
    for c in range(3):
        table[c][missing] = -CHANNEL_SCALES[c]
    return table


@pytest.fixture(scope="session")
def toy_materials(tmp_path_factory) -> Path:
    """A folder of 8 small-but-real MERL files (Lambert + Blinn–Phong, random colours)."""
    import frenbrdf

    folder = tmp_path_factory.mktemp("toy-materials")
    rng = np.random.default_rng(7)
    for i in range(8):
        frenbrdf.write_merl(folder / f"toy-{i:02d}.binary", toy_table(rng))
    return folder


def tiny(method: str, data: Path, out: Path, **overrides):
    """A training config that trains in seconds on the CPU: on the tables alone (``paper``) unless
    ``augment`` is given, so that every tiny batch has its L_fre truth."""
    from frenbrdf.training import config_for

    fields = dict(data=str(data), out=str(out), epochs=4, batch_materials=2, lr=3e-3, context_samples=256,
                    query_samples=512, cache_dir=str(out.parent / "cache"), progress=False)
    cfg = config_for(method, augmentation=None if "augment" in overrides else "paper", **{**fields, **overrides})
    cfg.model.nbrdf.hidden = (16, 16)
    cfg.model.encoder.hidden, cfg.model.encoder.latent = (32, 32), 8
    cfg.model.decoder.hidden = (32,)
    cfg.loss.frequency.lmax, cfg.loss.frequency.slices = 11, (0, 30, 60)
    return cfg


def write_keras_h5(path: Path, layers, names=None) -> Path:
    """Writes ``(kernel, bias)`` pairs in Keras' layout, as float32 like Keras does."""
    import h5py

    names = names or [f"dense_{i + 1}" for i in range(len(layers))]
    with h5py.File(path, "w") as file:
        for name, (kernel, bias) in zip(names, layers, strict=True):
            group = file.create_group(f"{name}/{name}")
            group["kernel:0"] = np.asarray(kernel, dtype=np.float32)
            group["bias:0"] = np.asarray(bias, dtype=np.float32)
        file.create_group("lambda_1")  # the exp(x) − 1 layer: no weights
    return path


def random_layers(sizes, seed=0):
    """Random Keras-layout layers ``(kernel (in, out), bias (out,))`` of the given widths."""
    rng = np.random.default_rng(seed)
    return [(rng.normal(0, 0.5, (n_in, n_out)), rng.normal(0, 0.1, n_out))
            for n_in, n_out in itertools.pairwise(sizes)]


def constant_table(value: float) -> np.ndarray:
    """A MERL table of one constant reflectance, missing below the horizon."""
    import frenbrdf

    table = np.full((3, 90, 90, 180), value)
    table[:, ~frenbrdf.merl_above_horizon()] = -1.0
    return table


def random_nbrdf_params(hidden=(8,), seed: int = 0):
    """Random weights of one small NBRDF (a leading batch of 1), as :class:`frenbrdf.NBRDF` takes them."""
    import torch

    from frenbrdf.models import NBRDFConfig

    generator = torch.Generator().manual_seed(seed)
    return [torch.randn(1, *s, generator=generator) * 0.3 for s in NBRDFConfig(hidden).shapes()]


#: Every augmentation kind at once (the drawer's tests).
EVERY_KIND = {"mix": 0.3, "gain": 0.3, "procedural": 0.3, "preset": "custom"}

@pytest.fixture(scope="module")
def prepared(toy_materials, tmp_path_factory):
    """The toy materials prepared once for the module (6 train, 1 validation, 1 test), albedos included."""
    cfg = tiny("frenbrdf", toy_materials, tmp_path_factory.mktemp("prepared") / "run", batch_materials=6,
               split=(0.75, 0.125, 0.125), augment=EVERY_KIND)
    files = {path.stem: path for path in list_materials(toy_materials)}
    return cfg, prepare(cfg, split_materials(files, cfg.seed, cfg.split), files)
