"""Shared fixtures: synthetic MERL tables and the published data beside the checkout."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

# CI runs the same examples every time, so a red run is reproducible; locally each run
# explores new ones.
settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


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
