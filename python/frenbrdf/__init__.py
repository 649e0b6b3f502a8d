"""frenbrdf: frequency-rectified neural BRDFs (FreNBRDF), with a Rust core.

The public API is re-exported here; ``frenbrdf._native`` is private.
"""

from . import sht
from ._native import __version__
from .coords import (
    directions_to_rusinkiewicz,
    half_diff_vectors,
    rusinkiewicz_to_directions,
    rusinkiewicz_to_half_diff,
)
from .exceptions import MerlFormatError
from .knn import KnnInterpolator, knn_interpolate
from .merl import (
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
from .training import Run, TrainConfig, TrainResult, config_for, train

__all__ = [
    "__version__",
    "sht",
    "KnnInterpolator",
    "MerlFormatError",
    "Model",
    "NBRDF",
    "Run",
    "TrainConfig",
    "TrainResult",
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
    "read_merl",
    "rusinkiewicz_to_directions",
    "rusinkiewicz_to_half_diff",
    "train",
    "valid_mask",
    "write_merl",
]
