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
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from ..io.atomic import atomic_path
from ..io.merl import SHAPE, merl_lookup_directions
from .lighting import LIGHTS, environment_radiance

#: The largest render (pixels per side): a size read from the command line or a config is checked against it.
MAX_RESOLUTION = 8192
#: Pixels per tile: a render is built a band of rows at a time, each costing about 8 KB a pixel while it is built
#: (every lit (pixel, light) pair's directions, radiance and BRDF value), so about 150 MB beyond the image at any
#: resolution.
TILE_PIXELS = 1 << 14
#: Scenes up to this size keep their tiles' geometry (at most :data:`CACHED_TILES` tiles, about 35 MB each): their
#: renders repeat (training's validation renders at 64², evaluation's thousands of edits at 128²). A larger scene's
#: tiles are built afresh, so that its memory stays that of one tile.
CACHED_RESOLUTION, CACHED_TILES = 256, 8
#: Renders of at least this many tiles (1024² and up: a few seconds or more) show a progress bar where asked to.
PROGRESS_TILES = 64

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
    """Every (pixel, light) pair of a tile (image rows ``start … stop − 1``) with the light above the pixel's horizon."""

    n_pixels: int  # pixels of the tile
    pixel: np.ndarray  # (K,) the tile's pixel (flat index within the tile) of each pair
    wi: np.ndarray  # (K, 3) local incident direction
    wo: np.ndarray  # (K, 3) local outgoing (view) direction
    radiance: np.ndarray  # (K, 3) incident radiance × cos θ_i × solid angle


def _tiles(scene: Scene) -> list[tuple[int, int]]:
    """The image's tiles: bands of whole rows ``(start, stop)``, each of at most :data:`TILE_PIXELS` pixels (one row
    at least)."""
    n = scene.resolution
    rows = max(1, TILE_PIXELS // n)
    return [(start, min(start + rows, n)) for start in range(0, n, rows)]


def _lights(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """The scene's light directions ``(L, 3)`` (unit, world space) and their radiance ``(L, 3)`` (× solid angle for the
    environment's directions): the directional lights, then the environment's."""
    lights = np.asarray(scene.light_directions, dtype=np.float64)
    lights /= np.linalg.norm(lights, axis=-1, keepdims=True)
    light_radiance = np.asarray(scene.light_colors, dtype=np.float64)
    if scene.environment_samples:
        env = _fibonacci_sphere(scene.environment_samples)
        lights = np.concatenate([lights, env])
        light_radiance = np.concatenate(
            [light_radiance, environment_radiance(env) * (4 * np.pi / scene.environment_samples)])
    return lights, light_radiance


def _normals(scene: Scene, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
    """The sphere's pixels among image rows ``start … stop − 1`` (flat indices within those rows) and their normals
    ``(P, 3)`` (orthographic camera looking down −z, image row 0 at the top)."""
    n = scene.resolution
    coords = (np.arange(n) + 0.5) / n * 2 - 1
    x, y = np.meshgrid(coords, -coords[start:stop])
    r2 = (x * x + y * y).reshape(-1)
    pixels = np.flatnonzero(r2 < 1)
    return pixels, np.stack([x.reshape(-1)[pixels], y.reshape(-1)[pixels], np.sqrt(1 - r2[pixels])], axis=-1)


def _tile_geometry(scene: Scene, start: int, stop: int) -> _Geometry:
    """The lit (pixel, light) pairs of image rows ``start … stop − 1``: about 4.5 KB a pixel while built."""
    pixels, normal = _normals(scene, start, stop)
    # A tangent frame per pixel (any one: the BRDFs are isotropic).
    helper = np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    tangent = np.cross(helper, normal)
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    bitangent = np.cross(normal, tangent)
    frame = np.stack([tangent, bitangent, normal], axis=1)  # (P, 3, 3): rows are the local axes

    lights, light_radiance = _lights(scene)
    wi = np.einsum("pij,lj->pli", frame, lights)
    wo = np.broadcast_to(frame[:, None, :, 2], wi.shape)  # the camera looks along −z: wo = world +z, in local axes
    lit = (wi[..., 2] > 0) & np.any(light_radiance, axis=-1)[None]
    pixel_index = np.broadcast_to(pixels[:, None], lit.shape)[lit]
    radiance = light_radiance[None] * wi[..., 2:3]
    return _Geometry((stop - start) * scene.resolution, pixel_index, wi[lit], np.ascontiguousarray(wo[lit]),
                     radiance[lit])


_cached_geometry = functools.lru_cache(maxsize=CACHED_TILES)(_tile_geometry)


def _geometry(scene: Scene, start: int, stop: int) -> _Geometry:
    """:func:`_tile_geometry`, kept for a scene of at most :data:`CACHED_RESOLUTION` pixels a side."""
    return (_cached_geometry if scene.resolution <= CACHED_RESOLUTION else _tile_geometry)(scene, start, stop)


def _tile_nbrdf_inputs(scene: Scene, start: int, stop: int, mapping, ordered: bool) -> tuple[np.ndarray, np.ndarray]:
    """(H, D) and f_ref at a tile's pairs: the same for every NBRDF sharing a mapping (and being ordered or not)."""
    from ..models.nbrdf import nbrdf_coordinates

    geometry = _geometry(scene, start, stop)
    return nbrdf_coordinates(geometry.wi, geometry.wo, ordered), mapping.reference_at(geometry.wi, geometry.wo)


_cached_nbrdf_inputs = functools.lru_cache(maxsize=2 * CACHED_TILES)(_tile_nbrdf_inputs)


def _brdf_values(source, scene: Scene, start: int, stop: int) -> np.ndarray:
    """The BRDF at every lit (pixel, light) pair of a tile of the scene, ``(K, 3)``."""
    from ..models.nbrdf import NBRDF

    geometry = _geometry(scene, start, stop)
    if isinstance(source, NBRDF):
        inputs = _cached_nbrdf_inputs if scene.resolution <= CACHED_RESOLUTION else _tile_nbrdf_inputs
        coords, reference = inputs(scene, start, stop, source.mapping, source.ordered)
        return source.mapping.inverse(source.mapped(coords), reference)
    if isinstance(source, np.ndarray):
        if source.shape != SHAPE:
            raise ValueError(f"a MERL table must have shape {SHAPE}, got {source.shape}")
        return np.maximum(merl_lookup_directions(source, geometry.wi, geometry.wo, method="trilinear"), 0.0)
    if callable(source):
        return np.asarray(source(geometry.wi, geometry.wo), dtype=np.float64)
    raise TypeError(f"cannot render a {type(source).__name__}: pass a MERL table, an NBRDF or a callable")


def _named(source) -> str:
    """What a message calls the BRDF: its file where it has one (an NBRDF's, a measurement's), else its type."""
    for attribute in ("source", "path"):
        where = getattr(source, attribute, None)
        if isinstance(where, (str, os.PathLike)) and os.fspath(where):
            return f"of {os.fspath(where)}"
    return f"({type(source).__name__})"


def _linear_tile(source, scene: Scene, start: int, stop: int) -> np.ndarray:
    """Linear outgoing radiance of image rows ``start … stop − 1``, ``(stop − start, resolution, 3)``."""
    geometry = _geometry(scene, start, stop)
    values = _brdf_values(source, scene, start, stop)
    if values.shape != geometry.wi.shape:
        raise ValueError(f"the BRDF returned shape {values.shape}, expected {geometry.wi.shape}")
    if not np.all(np.isfinite(values)):
        raise ValueError(f"the BRDF {_named(source)} returned NaN or inf values")
    contributions = values * geometry.radiance
    # Each pixel sums its lights in the same order as over the whole image: tiles change no bit of the result.
    image = np.stack([np.bincount(geometry.pixel, contributions[:, c], minlength=geometry.n_pixels)
                      for c in range(3)], axis=-1)
    return image.reshape(stop - start, scene.resolution, 3)


def _tiles_shown(scene: Scene, progress: bool) -> Iterable[tuple[int, int]]:
    """:func:`_tiles`, behind a progress bar where asked for and the render is large (a render of 8192² takes minutes
    on two cores: without a bar it would look hung)."""
    tiles = _tiles(scene)
    return tqdm(tiles, desc="render", unit="band", leave=False, disable=not progress or len(tiles) < PROGRESS_TILES)


def render_linear(source, scene: Scene = Scene(), *, progress: bool = False) -> np.ndarray:
    """Linear outgoing radiance ``(resolution, resolution, 3)``; background 0.

    Rendered in tiles of rows (:data:`TILE_PIXELS` pixels), so that the memory beyond the image (8 bytes a value)
    stays a few hundred MB whatever the resolution; ``progress`` shows a bar over them for a large render."""
    image = np.empty((scene.resolution, scene.resolution, 3))
    for start, stop in _tiles_shown(scene, progress):
        image[start:stop] = _linear_tile(source, scene, start, stop)
    return image


def material_mask(scene: Scene = Scene()) -> np.ndarray:
    """The lit material pixels ``(resolution, resolution)`` bool: on the sphere, with any light above
    their horizon. Image metrics are computed over these, not over the background."""
    lights, light_radiance = _lights(scene)
    lights = lights[light_radiance.any(axis=-1)]
    mask = np.zeros((scene.resolution, scene.resolution), dtype=bool)
    for start, stop in _tiles(scene):
        pixels, normal = _normals(scene, start, stop)
        # cos θ_i of a light is its direction's z in the pixel's frame: the normal's dot product with it.
        mask[start:stop].reshape(-1)[pixels] = np.any(normal @ lights.T > 0, axis=-1)
    return mask


def tonemap(radiance: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Exposure → clamp to [0, 1] → gamma 2.2."""
    return np.clip(radiance * exposure, 0.0, 1.0) ** (1 / 2.2)


def render(source, scene: Scene = Scene(), *, progress: bool = False) -> np.ndarray:
    """A display image in [0, 1], ``(resolution, resolution, 3)``: :func:`tonemap` of :func:`render_linear`, tile by
    tile (no second image-sized array); ``progress`` as there."""
    image = np.empty((scene.resolution, scene.resolution, 3))
    for start, stop in _tiles_shown(scene, progress):
        image[start:stop] = tonemap(_linear_tile(source, scene, start, stop), scene.exposure)
    return image


def save_png(path: str | os.PathLike, image: np.ndarray) -> None:
    """Writes an image in [0, 1] ``(H, W, 3)`` as an 8-bit PNG, atomically.

    The bytes are those matplotlib makes of a float image (× 255, truncated; NaN pixels transparent black), made a
    band of rows at a time: matplotlib's own conversion holds two float copies of the image with an alpha channel
    (4 GB at 8192²)."""
    import matplotlib.image

    image = np.asarray(image)
    rgba = np.empty(image.shape[:2] + (4,), dtype=np.uint8)
    rows = max(1, TILE_PIXELS // max(1, image.shape[1]))
    for start in range(0, image.shape[0], rows):
        block, out = np.clip(image[start:start + rows], 0, 1), rgba[start:start + rows]
        nan = np.isnan(block).any(axis=-1)
        block[nan] = 0
        out[..., :3] = block * 255  # the cast truncates, as matplotlib's astype does
        out[..., 3] = np.where(nan, 0, 255)
    with atomic_path(path) as temporary:
        matplotlib.image.imsave(temporary, rgba)


def save_figure(figure, path: str | os.PathLike, dpi: int = 100) -> None:
    """Writes a matplotlib figure as a PNG, atomically (temporary file in the same folder, then rename)."""
    with atomic_path(path) as temporary:
        figure.savefig(temporary, dpi=dpi)
