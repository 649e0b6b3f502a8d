"""frenbrdf: frequency-rectified neural BRDFs (FreNBRDF), with a Rust core.

The public API is re-exported here; ``frenbrdf._native`` is private.
"""

import importlib

from ._native import __version__
from .exceptions import BsdfFormatError, MerlFormatError
from .io.bsdf import MeasuredBSDF, read_bsdf
from .io.formats import read_material, read_samples
from .io.merl import (
    merl_above_horizon,
    merl_angles_to_bin,
    merl_bin_angles,
    merl_bin_directions,
    merl_bin_grid,
    merl_bin_rusinkiewicz,
    merl_bin_to_angles,
    merl_lookup,
    merl_lookup_directions,
    read_merl,
    valid_mask,
    write_merl,
)
from .models import NBRDF, Model, interpolate
from .numerics import sht
from .numerics.coords import (
    directions_to_rusinkiewicz,
    half_diff_vectors,
    rusinkiewicz_to_directions,
    rusinkiewicz_to_half_diff,
)
from .numerics.knn import KnnInterpolator, knn_interpolate
from .render.viewer import view
from .training import Run, TrainConfig, config_for, train


def __getattr__(name: str):
    # ``frenbrdf.render.mitsuba`` imports Mitsuba 3, which takes seconds: load it on first use only.
    if name == "mitsuba":
        return importlib.import_module(".render.mitsuba", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "__version__",
    "sht",
    "KnnInterpolator",
    "BsdfFormatError",
    "MeasuredBSDF",
    "MerlFormatError",
    "Model",
    "NBRDF",
    "Run",
    "TrainConfig",
    "config_for",
    "interpolate",
    "directions_to_rusinkiewicz",
    "half_diff_vectors",
    "knn_interpolate",
    "merl_above_horizon",
    "merl_angles_to_bin",
    "merl_bin_angles",
    "merl_bin_directions",
    "merl_bin_grid",
    "merl_bin_rusinkiewicz",
    "merl_bin_to_angles",
    "merl_lookup",
    "merl_lookup_directions",
    "read_bsdf",
    "read_material",
    "read_merl",
    "read_samples",
    "rusinkiewicz_to_directions",
    "rusinkiewicz_to_half_diff",
    "train",
    "valid_mask",
    "view",
    "write_merl",
]
