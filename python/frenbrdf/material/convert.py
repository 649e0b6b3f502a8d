"""``frenbrdf convert``: a measured material into another format.

- an RGL ``.bsdf`` measurement → a MERL ``.binary`` table (evaluated at every bin's directions);
- a ``.bsdf`` or a MERL table → a CSV or NPZ of samples at random valid MERL bins, the form
  ``frenbrdf reconstruct`` reads (:mod:`frenbrdf.material.measurements`; a ``.bsdf`` is evaluated at each
  bin's pair in a random order: a measurement need not be reciprocal, a table keeps one order).

The output is checked before any work (its suffix, its folder; an existing file is replaced only
when asked) and written atomically.

Examples
--------
>>> from frenbrdf.material.convert import convert
>>> convert("paper_white_rgb.bsdf", "paper_white.binary")                 # doctest: +SKIP
>>> convert("paper_white_rgb.bsdf", "paper_white.csv", samples=4000)      # doctest: +SKIP
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_path, save_csv
from ..io.measured import SUFFIXES, read_table
from ..io.merl import write_merl
from ..io.outputs import check_output_file
from ..io.paths import input_file
from .measurements import FORMS, read_measurements

#: What each output suffix holds.
OUTPUTS = {".binary": "a MERL table", ".csv": "samples (CSV)", ".npz": "samples (NPZ)"}


def convert(source: str | os.PathLike, dest: str | os.PathLike, *, samples: int | None = 4000, seed: int = 0,
            overwrite: bool = False) -> Path:
    """Converts ``source`` (a ``.bsdf`` or ``.binary`` file) into ``dest``, whose suffix picks the format
    (:data:`OUTPUTS`). ``samples``: CSV/NPZ output only, the random valid bins drawn (from ``seed``), None for
    all. Returns ``dest``.

    Raises
    ------
    FileExistsError
        ``dest`` exists and ``overwrite`` is false.
    ValueError
        A bad suffix, ``dest`` equal to ``source``, or a malformed input (the message names the file).
    """
    source = input_file(source, "material file")
    if source.suffix.lower() not in SUFFIXES:
        raise ValueError(f"{source}: convert reads a .bsdf measurement or a MERL .binary file")
    dest = check_output_file(dest, tuple(OUTPUTS), option="output", overwrite=overwrite, inputs=(source,))
    dest.parent.mkdir(parents=True, exist_ok=True)  # a folder that can be created (checked above)
    if dest.suffix.lower() == ".binary":
        write_merl(dest, read_table(source))
        return dest
    measured = read_measurements(source, samples=samples, seed=seed)
    columns = dict(zip(FORMS["vectors"], np.concatenate([measured.wi, measured.wo, measured.values], axis=1).T))
    if dest.suffix.lower() == ".npz":
        with atomic_path(dest) as temporary, open(temporary, "wb") as file:
            np.savez(file, **columns)
    else:  # Python floats print exactly (shortest round-trip repr)
        save_csv(dest, [dict(zip(columns, row)) for row in np.stack(list(columns.values()), axis=1).tolist()])
    return dest
