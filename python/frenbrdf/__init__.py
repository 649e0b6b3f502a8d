"""frenbrdf: frequency-rectified neural BRDFs (FreNBRDF), with a Rust core.

The public API is re-exported here; ``frenbrdf._native`` is private. Each name is imported on its first use, so
that ``import frenbrdf`` and the command line start without waiting for torch (about 2 s): ``frenbrdf --help`` is
quick, and a Ctrl-C while torch loads ends as one line.
"""

from __future__ import annotations

import importlib
import importlib.util

from ._native import __version__

#: Where each public name is defined, by module.
_PUBLIC = {
    ".exceptions": ["BsdfFormatError", "MerlFormatError"],
    ".io.bsdf": ["MeasuredBSDF", "read_bsdf"],
    ".io.formats": ["read_material", "read_samples"],
    ".io.merl": ["merl_above_horizon", "merl_angles_to_bin", "merl_bin_angles", "merl_bin_directions", "merl_bin_grid",
                 "merl_bin_rusinkiewicz", "merl_bin_to_angles", "merl_lookup", "merl_lookup_directions", "read_merl",
                 "valid_mask", "write_merl"],
    ".models": ["NBRDF", "Model", "interpolate"],
    ".numerics.coords": ["directions_to_rusinkiewicz", "half_diff_vectors", "rusinkiewicz_to_directions",
                         "rusinkiewicz_to_half_diff"],
    ".numerics.knn": ["KnnInterpolator", "knn_interpolate"],
    ".render.viewer": ["view"],
    ".training": ["Run", "TrainConfig", "config_for", "train"],
}
#: Public modules by their short names (``frenbrdf.mitsuba`` imports Mitsuba 3, which takes seconds).
_MODULES = {"sht": ".numerics.sht", "mitsuba": ".render.mitsuba"}
_DEFINED_IN = {name: module for module, names in _PUBLIC.items() for name in names}


def __getattr__(name: str):
    if name in _MODULES:
        value = importlib.import_module(_MODULES[name], __name__)
    elif name in _DEFINED_IN:
        value = getattr(importlib.import_module(_DEFINED_IN[name], __name__), name)
    elif importlib.util.find_spec(f"{__name__}.{name}") is not None:  # a subpackage: frenbrdf.io without its import
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # once: later uses find it without this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


__all__ = ["__version__", "sht", *_DEFINED_IN]
