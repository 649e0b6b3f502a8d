"""The page: one self-contained HTML file (``page.html`` with ``viewer.js`` and the material's data inlined).

The data block holds the networks' weights as float32 in one RGBA texture (each row one unit of a layer: its
weights four to a texel, and in the texel after them the biases of the four units starting at that row), each
network's layer widths, order input and mapping, the edit's keyframes, and the lights of
:class:`frenbrdf.render.Scene` (key, fill and rim, the environment's 48 directions) so that the page's sphere
is the metric renderer's.
"""

from __future__ import annotations

import base64
import html
import json
import math
from importlib import resources

import numpy as np

from ...models.mapping import LogRelativeMapping
from ...models.nbrdf import NBRDF
from ..lighting import KEY_LIGHT
from ..renderer import Scene, _lights
from .sources import Edit, Material, mapping_state

#: The page's settings before the user or the URL changes them.
DEFAULTS = {"exposure": 1.0, "t": 0.5, "size": 256, "theta_i": 45, "phi_d": 90, "chunk": 4}


def _pad(n: int) -> int:
    return 4 * math.ceil(n / 4)


class _Texture:
    """Networks packed into one float32 RGBA texture (see the module docstring)."""

    def __init__(self):
        self.blocks: list[np.ndarray] = []  # (rows, texels, 4) per network, widths not yet equal
        self.rows = 0
        self.networks: list[dict] = []
        self._index: dict[int, int] = {}

    def add(self, nbrdf: NBRDF) -> int:
        """The network's index, packing it the first time it is seen."""
        if id(nbrdf) in self._index:
            return self._index[id(nbrdf)]
        weights, biases = nbrdf.params[0::2], nbrdf.params[1::2]
        widths = [int(weights[0].shape[2])] + [int(w.shape[1]) for w in weights]
        blocks = []
        for weight, bias in zip(weights, biases, strict=True):
            out, fan_in = weight.shape[1:]
            block = np.zeros((_pad(out), _pad(fan_in) // 4 + 1, 4), dtype=np.float32)
            rows = np.zeros((_pad(out), _pad(fan_in)), dtype=np.float32)
            rows[:out, :fan_in] = weight[0].numpy()
            block[:, :-1] = rows.reshape(_pad(out), -1, 4)
            # The biases of units 4j … 4j + 3 go in the last texel of row 4j.
            block[0::4, -1] = np.pad(bias[0].numpy(), (0, _pad(out) - out)).reshape(-1, 4)
            blocks.append(block)
        self.networks.append({"widths": widths, "row": self.rows, "ordered": nbrdf.ordered,
                              "mapping": list(mapping_state(nbrdf.mapping))})
        self.blocks += blocks
        self.rows += sum(len(b) for b in blocks)
        self._index[id(nbrdf)] = len(self.networks) - 1
        return len(self.networks) - 1

    def data(self) -> dict:
        width = max(b.shape[1] for b in self.blocks)
        texture = np.zeros((self.rows, width, 4), dtype="<f4")
        row = 0
        for block in self.blocks:
            texture[row:row + len(block), :block.shape[1]] = block
            row += len(block)
        return {"width": width, "height": self.rows, "data": base64.b64encode(texture.tobytes()).decode("ascii")}


def _lights_data() -> dict:
    """The metric renderer's lights (:class:`frenbrdf.render.Scene`'s defaults), as the page takes them."""
    scene = Scene()
    directions, radiance = _lights(scene)
    n_fixed = len(scene.light_directions)
    pairs = [[[float(v) for v in d], [float(v) for v in r]] for d, r in zip(directions, radiance, strict=True)]
    return {"key": {"radiance": pairs[0][1]}, "fixed": pairs[1:n_fixed], "environment": pairs[n_fixed:]}


def _key_angles() -> list[float]:
    """The key light's direction as (θ, φ) in degrees: θ from the camera axis +z, φ from +x towards +y."""
    x, y, z = np.asarray(KEY_LIGHT[0]) / np.linalg.norm(KEY_LIGHT[0])
    return [math.degrees(math.acos(z)), math.degrees(math.atan2(y, x))]


def page_data(materials: list[Material], edit: Edit | None = None, title: str | None = None) -> dict:
    """The data block of a page showing one material, or the edit between two."""
    texture = _Texture()
    if edit is None:
        (material,) = materials
        texture.add(material.nbrdf)
        mapping: LogRelativeMapping = material.nbrdf.mapping
        edit_data = None
    else:
        keyframes = [texture.add(k) for k in edit.keyframes]
        edit_data = {"keyframes": keyframes, "a": texture.add(edit.a.nbrdf), "b": texture.add(edit.b.nbrdf),
                     "modes": list(edit.modes)}
        mapping = edit.mapping
    return {"format": "frenbrdf-view", "version": 1,
            "title": title or " ↔ ".join(m.name for m in materials),
            "materials": [{"name": m.name, "origin": m.origin} for m in materials],
            "texture": texture.data(), "networks": texture.networks, "mapping": list(mapping_state(mapping)),
            "edit": edit_data, "lights": _lights_data(), "defaults": {**DEFAULTS, "light": _key_angles()}}


def page_html(data: dict) -> str:
    """The HTML file of a page's data."""
    folder = resources.files(__package__)
    template = folder.joinpath("page.html").read_text(encoding="utf-8")
    script = folder.joinpath("viewer.js").read_text(encoding="utf-8")
    # "</" inside the data block would end the <script> element: JSON lets it be written "<\/".
    block = json.dumps(data, ensure_ascii=False, separators=(",", ":")).replace("</", "<\\/")
    template = template.replace("<title>frenbrdf view</title>", f"<title>{html.escape(data['title'])} — frenbrdf view</title>")
    before, rest = template.split("/*DATA*/")
    middle, after = rest.split("/*SCRIPT*/")
    return before + block + middle + script + after
