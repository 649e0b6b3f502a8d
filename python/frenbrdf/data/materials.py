"""One loader for material files, used by ``frenbrdf render`` and the Mitsuba plugin.

:func:`load_material_file` reads any supported file into what both renderers take: a
MERL table array or a :class:`frenbrdf.NBRDF` (:func:`frenbrdf.render.render` renders
either, :func:`frenbrdf.render.mitsuba.load_material` turns either into the plugin's
material).

Examples
--------
>>> from frenbrdf.data.materials import load_material_file
>>> from frenbrdf.render import render
>>> image = render(load_material_file("gold-paint.h5"))       # doctest: +SKIP
"""

from __future__ import annotations

import os

#: What :func:`load_material_file` reads, for messages.
SUPPORTED = ("a MERL .binary file, an RGL .bsdf measurement, an NBRDF saved by fit-nbrdf (.pt) or a published "
             "Keras NBRDF (.h5)")


def load_material_file(path: str | os.PathLike):
    """Reads a material file.

    Parameters
    ----------
    path
        A MERL ``.binary`` file; an RGL ``.bsdf`` measurement; an NBRDF saved by :func:`frenbrdf.data.fitting.save_nbrdf`
        (``.pt``); or a published Keras NBRDF ``.h5`` (:mod:`frenbrdf.data.nbrdf_import`).
        Other names are read as a MERL file when they have a MERL file's size, else as a
        saved NBRDF.

    Returns
    -------
    numpy.ndarray, frenbrdf.io.bsdf.MeasuredBSDF or frenbrdf.NBRDF
        The MERL table ``(3, 90, 90, 180)`` in physical units (missing bins negative), the
        measurement (callable like an NBRDF), or one NBRDF (a Keras file's network with its
        output ``exp(x) − 1``).

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        The file is none of the supported formats (the message names it).
    """
    from ..io.merl import FILE_BYTES, read_merl
    from ..io.paths import input_file
    from .fitting import load_nbrdf

    path = input_file(path, "material file")  # a folder, FIFO or link loop is named as such, never read
    suffix = path.suffix.lower()  # GOLD.H5 is read as every other command reads it
    if suffix == ".h5":
        from .nbrdf_import import keras_nbrdf, load_keras_nbrdf

        return keras_nbrdf(load_keras_nbrdf(path))
    if suffix == ".pt":
        return load_nbrdf(path)
    if suffix == ".bsdf":
        from ..io.bsdf import read_bsdf

        return read_bsdf(path)
    if suffix == ".binary" or path.stat().st_size == FILE_BYTES:
        return read_merl(path)
    try:
        return load_nbrdf(path)
    except ValueError as error:
        raise ValueError(f"{path}: neither a MERL file (those hold {FILE_BYTES} bytes, this one "
                         f"{path.stat().st_size}) nor a saved NBRDF ({error}); expected {SUPPORTED}") from None
