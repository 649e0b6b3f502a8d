"""``frenbrdf convert``: a measured material, or a file of samples, into another format.

- an RGL ``.bsdf`` measurement → a MERL ``.binary`` table (evaluated at every bin's directions);
- a ``.bsdf`` or a MERL table → a CSV, NPZ or ASTM E1392 (``.astm``) file of samples at random valid MERL
  bins or at the pairs of a sampling pattern (a device imitated), the form ``frenbrdf reconstruct`` reads (:func:`frenbrdf.io.read_samples`; a ``.bsdf`` is evaluated at
  each bin's pair in a random order: a measurement need not be reciprocal, a table keeps one order);
- a file of samples (``.csv``, ``.npz``, ``.astm``) → another, every sample as it is (ASTM files to CSV and
  back). Scattered samples make no MERL table: ``frenbrdf reconstruct`` fits a material to them and writes one.

The output is checked before any work (its suffix, its folder; an existing file is replaced only
when asked) and written atomically.

Examples
--------
>>> from frenbrdf.material.convert import convert
>>> convert("paper_white_rgb.bsdf", "paper_white.binary")                 # doctest: +SKIP
>>> convert("paper_white_rgb.bsdf", "paper_white.csv", samples=4000)      # doctest: +SKIP
>>> convert("paper_white_rgb.bsdf", "gonio.astm", samples=1500, pattern="gonioreflectometer")  # doctest: +SKIP
>>> convert("gonio-export.astm", "gonio-export.csv")                     # doctest: +SKIP
"""

from __future__ import annotations

import os
from pathlib import Path

from ..io.formats import FORMATS, format_of, read_samples, read_table, write_material, write_samples
from ..io.outputs import check_output_file
from ..io.paths import input_file
from ..io.patterns import DEFAULT as DEFAULT_PATTERN

#: What each output suffix holds: the formats frenbrdf writes a measured material or its samples in.
OUTPUTS = {suffix: entry.holds for suffix, entry in FORMATS.items()
           if entry.write and entry.role in ("measurement", "samples")}


def convert(source: str | os.PathLike, dest: str | os.PathLike, *, samples: int | None = 4000, seed: int = 0,
            pattern: str = DEFAULT_PATTERN, overwrite: bool = False) -> Path:
    """Converts ``source`` (a ``.bsdf`` or ``.binary`` file, or a file of samples) into ``dest``, whose suffix
    picks the format (:data:`OUTPUTS`). ``samples`` and ``pattern``: a material into samples only, the random
    valid bins drawn (from ``seed``; None for all), or ``samples`` pairs of another sampling pattern
    (:data:`frenbrdf.io.patterns.PATTERNS`: the device imitated); a file of samples is converted whole. Returns
    ``dest``.

    Raises
    ------
    FileExistsError
        ``dest`` exists and ``overwrite`` is false.
    ValueError
        A bad suffix, ``dest`` equal to ``source``, samples into a ``.binary``, or a malformed input (the message
        names the file).
    """
    source = input_file(source, "material file")
    entry = format_of(source, ("measurement", "samples"), "convert")  # checked before any work
    dest = check_output_file(dest, tuple(OUTPUTS), option="output", overwrite=overwrite, inputs=(source,))
    if entry.role == "samples" and dest.suffix.lower() == ".binary":
        raise ValueError(f"{source}: scattered samples make no MERL table ({dest.name}); `frenbrdf reconstruct "
                         f"{source.name} --out FOLDER` fits a material to them and writes its table")
    dest.parent.mkdir(parents=True, exist_ok=True)  # a folder that can be created (checked above)
    if dest.suffix.lower() == ".binary":
        write_material(dest, read_table(source))
    else:
        write_samples(dest, read_samples(source, samples=samples, seed=seed, pattern=pattern))
    return dest
