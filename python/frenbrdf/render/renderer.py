"""A deterministic renderer for metrics: one sphere, a fixed camera, fixed lights.

Truth and prediction are lit by exactly the same directions: three directional lights
and an environment integrated with a fixed set of sample directions (a Fibonacci
sphere), so comparisons carry no Monte Carlo noise. Rendering is linear in the BRDF,
which :func:`render_linear` exposes (the truth of an interpolated material is the
interpolation of the truths' renders). :func:`tonemap` turns radiance into a display
image: exposure → clamp to [0, 1] → gamma 2.2.

Any BRDF source works: a MERL table ``(3, 90, 90, 180)``, an :class:`frenbrdf.NBRDF`
(one material), or any callable ``brdf(wi, wo) -> (..., 3)`` on local unit directions.

Examples
--------
>>> import frenbrdf
>>> from frenbrdf.render import render
>>> image = render(frenbrdf.read_merl("gold-paint.binary"))        # doctest: +SKIP
>>> image.shape                                                    # doctest: +SKIP
(256, 256, 3)
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass

import numpy as np

from ..io.atomic import atomic_path
from ..io.merl import SHAPE, merl_lookup_directions
from .lighting import LIGHTS, environment_radiance

#: The largest render (pixels per side): a size read from the command line or a config is checked against it.
MAX_RESOLUTION = 8192

__all__ = ["Scene", "environment_radiance", "material_mask", "render", "render_linear", "save_figure", "save_png",
           "tonemap"]


@dataclass(frozen=True)
class Scene:
    """Camera, lights and tone mapping of :func:`render`."""

    resolution: int = 256
    """Image width and height in pixels (orthographic camera looking down −z at a unit sphere)."""
    light_directions: tuple[tuple[float, float, float], ...] = tuple(direction for direction, _ in LIGHTS)
    """Directional lights (towards the light, world space; normalised): :data:`frenbrdf.render.lighting.LIGHTS`."""
    light_colors: tuple[tuple[float, float, float], ...] = tuple(colour for _, colour in LIGHTS)
    """Their irradiance (RGB, at normal incidence)."""
    environment_samples: int = 48
    """Fixed directions (Fibonacci sphere) integrating the environment."""
    exposure: float = 1.0
    """Radiance multiplier before clamping."""

    def __post_init__(self):
        problems = [f"{name} must be {rule}, got {value}" for name, value, ok, rule in (
            ("resolution", self.resolution, 8 <= self.resolution <= MAX_RESOLUTION, f"in 8 … {MAX_RESOLUTION}"),
            ("environment_samples", self.environment_samples, self.environment_samples >= 0, "≥ 0"),
            ("exposure", self.exposure, self.exposure > 0, "> 0")) if not ok]
        if problems:
            raise ValueError("invalid scene: " + "; ".join(problems))
        if len(self.light_directions) != len(self.light_colors):
            raise ValueError("one colour per light direction")


def _fibonacci_sphere(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = np.pi * (1 + 5**0.5) * i
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


@dataclass(frozen=True)
class _Geometry:
    """Every (pixel, light) pair with the light above the pixel's horizon."""

    n_pixels: int  # pixels of the image
    pixel: np.ndarray  # (K,) the image pixel (flat index) of each pair
    wi: np.ndarray  # (K, 3) local incident direction
    wo: np.ndarray  # (K, 3) local outgoing (view) direction
    radiance: np.ndarray  # (K, 3) incident radiance × cos θ_i × solid angle


@functools.lru_cache(maxsize=4)
def _geometry(scene: Scene) -> _Geometry:
    n = scene.resolution
    coords = (np.arange(n) + 0.5) / n * 2 - 1
    x, y = np.meshgrid(coords, -coords)  # image row 0 at the top
    r2 = (x * x + y * y).reshape(-1)
    pixels = np.flatnonzero(r2 < 1)
    normal = np.stack([x.reshape(-1)[pixels], y.reshape(-1)[pixels], np.sqrt(1 - r2[pixels])], axis=-1)
    # A tangent frame per pixel (any one: the BRDFs are isotropic).
    helper = np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    tangent = np.cross(helper, normal)
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    bitangent = np.cross(normal, tangent)
    frame = np.stack([tangent, bitangent, normal], axis=1)  # (P, 3, 3): rows are the local axes

    lights = np.asarray(scene.light_directions, dtype=np.float64)
    lights /= np.linalg.norm(lights, axis=-1, keepdims=True)
    light_radiance = np.asarray(scene.light_colors, dtype=np.float64)
    if scene.environment_samples:
        env = _fibonacci_sphere(scene.environment_samples)
        lights = np.concatenate([lights, env])
        light_radiance = np.concatenate(
            [light_radiance, environment_radiance(env) * (4 * np.pi / scene.environment_samples)])
    wi = np.einsum("pij,lj->pli", frame, lights)
    wo = np.broadcast_to(frame[:, None, :, 2], wi.shape)  # the camera looks along −z: wo = world +z, in local axes
    lit = (wi[..., 2] > 0) & light_radiance.any(axis=-1)[None]
    pixel_index = np.broadcast_to(pixels[:, None], lit.shape)[lit]
    radiance = light_radiance[None] * wi[..., 2:3]
    return _Geometry(n * n, pixel_index, wi[lit], np.ascontiguousarray(wo[lit]), radiance[lit])


@functools.lru_cache(maxsize=8)
def _nbrdf_inputs(scene: Scene, mapping, ordered: bool) -> tuple[np.ndarray, np.ndarray]:
    """(H, D) and f_ref at the scene's pairs: the same for every NBRDF sharing a mapping (and being ordered or not)."""
    from ..models.nbrdf import nbrdf_coordinates

    geometry = _geometry(scene)
    return nbrdf_coordinates(geometry.wi, geometry.wo, ordered), mapping.reference_at(geometry.wi, geometry.wo)


def _brdf_values(source, scene: Scene) -> np.ndarray:
    """The BRDF at every lit (pixel, light) pair of the scene, ``(K, 3)``."""
    from ..models.nbrdf import NBRDF

    geometry = _geometry(scene)
    if isinstance(source, NBRDF):
        coords, reference = _nbrdf_inputs(scene, source.mapping, source.ordered)
        return source.mapping.inverse(source.mapped(coords), reference)
    if isinstance(source, np.ndarray):
        if source.shape != SHAPE:
            raise ValueError(f"a MERL table must have shape {SHAPE}, got {source.shape}")
        return np.maximum(merl_lookup_directions(source, geometry.wi, geometry.wo, method="trilinear"), 0.0)
    if callable(source):
        return np.asarray(source(geometry.wi, geometry.wo), dtype=np.float64)
    raise TypeError(f"cannot render a {type(source).__name__}: pass a MERL table, an NBRDF or a callable")


def render_linear(source, scene: Scene = Scene()) -> np.ndarray:
    """Linear outgoing radiance ``(resolution, resolution, 3)``; background 0."""
    geometry = _geometry(scene)
    values = _brdf_values(source, scene)
    if values.shape != geometry.wi.shape:
        raise ValueError(f"the BRDF returned shape {values.shape}, expected {geometry.wi.shape}")
    if not np.all(np.isfinite(values)):
        raise ValueError("the BRDF returned NaN or inf values")
    contributions = values * geometry.radiance
    image = np.stack([np.bincount(geometry.pixel, contributions[:, c], minlength=geometry.n_pixels)
                      for c in range(3)], axis=-1)
    return image.reshape(scene.resolution, scene.resolution, 3)


def material_mask(scene: Scene = Scene()) -> np.ndarray:
    """The lit material pixels ``(resolution, resolution)`` bool: on the sphere, with any light above
    their horizon. Image metrics are computed over these, not over the background."""
    geometry = _geometry(scene)
    mask = np.zeros(geometry.n_pixels, dtype=bool)
    mask[geometry.pixel] = True
    return mask.reshape(scene.resolution, scene.resolution)


def tonemap(radiance: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Exposure → clamp to [0, 1] → gamma 2.2."""
    return np.clip(radiance * exposure, 0.0, 1.0) ** (1 / 2.2)


def render(source, scene: Scene = Scene()) -> np.ndarray:
    """A display image in [0, 1], ``(resolution, resolution, 3)``."""
    return tonemap(render_linear(source, scene), scene.exposure)


def save_png(path: str | os.PathLike, image: np.ndarray) -> None:
    """Writes an image in [0, 1] ``(H, W, 3)`` as an 8-bit PNG, atomically."""
    import matplotlib.image

    with atomic_path(path) as temporary:
        matplotlib.image.imsave(temporary, np.clip(image, 0, 1))


def save_figure(figure, path: str | os.PathLike, dpi: int = 100) -> None:
    """Writes a matplotlib figure as a PNG, atomically (temporary file in the same folder, then rename)."""
    with atomic_path(path) as temporary:
        figure.savefig(temporary, dpi=dpi)
