"""``frenbrdf view``: one self-contained HTML page that renders a neural material live in WebGL2.

The page evaluates the NBRDF per pixel in a fragment shader under a key light the user drags, the fill and rim
lights and the environment of :class:`frenbrdf.render.Scene` (so that its sphere is the metric renderer's image),
with BRDF Explorer's in-plane polar plot and θ_h × θ_d image; with two materials, an edit slider between them
(:mod:`frenbrdf.render.viewer.sources`). Nothing is fetched when it is opened: it works from disk and can be mailed.

Examples
--------
>>> import frenbrdf
>>> page = frenbrdf.view("gold/")                 # a reconstruct result folder; shown inline in Jupyter
>>> page.save("gold.html")                                                          # doctest: +SKIP
>>> html = frenbrdf.view("a.pt", "b.pt").html     # two materials and the edit between them  # doctest: +SKIP
"""

from __future__ import annotations

import html as _html
import os
from pathlib import Path

from ...models.nbrdf import NBRDF
from .page import page_data, page_html
from .sources import KEYFRAMES, Edit, Material, make_edit, read_material

__all__ = ["KEYFRAMES", "Edit", "Material", "View", "view", "write_view"]


class View:
    """A page: its HTML (:attr:`html`), shown inline by Jupyter, written by :meth:`save`."""

    def __init__(self, html: str, materials: list[Material], edit: Edit | None):
        #: The page: one self-contained HTML document.
        self.html = html
        self.materials = materials
        self.edit = edit

    def __str__(self) -> str:
        return self.html

    def _repr_html_(self) -> str:
        # An iframe keeps the page's script and styles apart from the notebook's.
        return (f'<iframe srcdoc="{_html.escape(self.html, quote=True)}" style="width: 100%; height: 620px; '
                'border: 0" sandbox="allow-scripts allow-downloads"></iframe>')

    def save(self, path: str | os.PathLike, *, overwrite: bool = False) -> Path:
        """Writes the page atomically (an existing file is replaced only with ``overwrite``)."""
        from ...io.atomic import write_text
        from ...io.outputs import check_output_file

        path = check_output_file(path, (".html", ".htm"), "path", overwrite=overwrite)
        write_text(path, self.html)
        return path


def _material(source, model, progress: bool) -> Material:
    if isinstance(source, Material):
        return source
    if isinstance(source, NBRDF):
        if len(source) != 1:
            raise ValueError(f"this NBRDF holds {len(source)} materials; index one first, e.g. nbrdf[0]")
        return Material(source, "material", "an NBRDF given in Python")
    return read_material(source, model=model, progress=progress)


def view(a, b=None, *, title: str | None = None, model=None, progress: bool = False) -> View:
    """The page of a material, or of two and the edit between them.

    Parameters
    ----------
    a, b
        Each a :class:`frenbrdf.NBRDF` (one material), or a path: a saved NBRDF (``.pt``), a Keras NBRDF (``.h5``),
        a ``reconstruct`` result folder, a MERL ``.binary`` file or an RGL ``.bsdf`` measurement (shown as the
        packaged model's fit).
    title
        The page's heading (default: the materials' names).
    model
        A :class:`frenbrdf.Model` that fits measurements and holds the edit's latent space (default: the model of
        a result folder's latent, else the packaged one).
    progress
        Show progress bars (a measurement's fit, the edit).

    Returns
    -------
    View
        ``.html`` is the page; Jupyter shows it inline.
    """
    materials = [_material(a, model, progress)]
    edit = None
    if b is not None:
        materials.append(_material(b, model, progress))
        edit = make_edit(*materials, model=model, progress=progress)
    return View(page_html(page_data(materials, edit, title)), materials, edit)


def write_view(inputs: list[str | os.PathLike], out: str | os.PathLike, *, overwrite: bool = False,
               model: str | None = None, title: str | None = None, progress: bool = True) -> tuple[Path, View]:
    """``frenbrdf view``: checks the output first (:func:`frenbrdf.io.outputs.check_output_file`), then builds the
    page of one or two inputs and writes it atomically."""
    from ...io.atomic import write_text
    from ...io.outputs import check_output_file
    from ...io.paths import input_file

    if not 1 <= len(inputs) <= 2:
        raise ValueError(f"view takes one or two materials, got {len(inputs)}")
    for given in inputs:
        if not Path(given).is_dir():
            input_file(given, "material file")  # missing or unreadable inputs are named before any work
    path = check_output_file(out, (".html",), overwrite=overwrite, inputs=inputs)
    loaded = None
    if model is not None:
        from ...models.autoencoder import load_model

        loaded = load_model(model)
    page = view(*inputs, title=title, model=loaded, progress=progress)
    write_text(path, page.html)
    return path, page
