"""Pictures of materials and their scores: the deterministic metric renderer (re-exported here, as
``frenbrdf.render`` always was), the lights, figures, image metrics against the truth, and the
Mitsuba 3 plugin under ``mitsuba/``."""

from .renderer import Scene, material_mask, render, render_linear, save_figure, save_png, tonemap

__all__ = ["Scene", "material_mask", "render", "render_linear", "save_figure", "save_png", "tonemap"]
