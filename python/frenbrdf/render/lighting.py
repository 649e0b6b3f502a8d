"""The lighting both renderers share: a soft sky and three directional lights.

:mod:`frenbrdf.render` (the metric renderer) integrates :func:`environment_radiance`
with fixed directions and uses all of :data:`LIGHTS`; :mod:`frenbrdf.render.mitsuba` bakes the
same sky into an environment map (with a small sun) and uses the key and fill lights.
World +y is up.
"""

from __future__ import annotations

import numpy as np

#: Directional lights as (direction towards the light, world space, not normalised;
#: irradiance RGB at normal incidence): key, fill, rim.
KEY_LIGHT = ((-0.5, 0.6, 0.62), (2.2, 2.1, 2.0))
FILL_LIGHT = ((0.7, 0.2, 0.68), (0.9, 0.95, 1.1))
RIM_LIGHT = ((0.0, -0.8, 0.3), (0.5, 0.5, 0.5))
#: The three lights: key, fill, rim.
LIGHTS = (KEY_LIGHT, FILL_LIGHT, RIM_LIGHT)


def environment_radiance(directions: np.ndarray) -> np.ndarray:
    """A soft sky: bluish above, warm near the horizon, dark ground. ``(..., 3)`` → RGB ``(..., 3)``."""
    up = directions[..., 1:2]  # world +y is up in the image
    sky = np.array([0.35, 0.45, 0.6]) * np.clip(up, 0, 1) + np.array([0.5, 0.42, 0.35]) * (1 - np.abs(up))
    ground = np.array([0.08, 0.07, 0.06])
    return np.where(up > 0, sky, ground) * 0.6
