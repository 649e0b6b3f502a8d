"""The scene of :func:`render_material`: a sphere under the shared sky (plus a sun) and two lights."""

from __future__ import annotations

import os

import numpy as np

from ..lighting import FILL_LIGHT, KEY_LIGHT, environment_radiance
from ..renderer import save_png, tonemap  # one tone mapping for both renderers
from .bsdf import register
from .material import _HANDLES, bsdf_dict, material_handle, release_handle
from .variants import _import_mitsuba

#: The largest Mitsuba render (pixels per side), below the metric renderer's: Mitsuba's film, its image and ours take
#: about 55 bytes a pixel whatever the samples per pixel (measured peak of ``frenbrdf render --mitsuba``: 1.7 GB at
#: 4096², so about 4.5 GB at 8192²; 64 samples per pixel take some 10 minutes per 2048² on two cores).
MAX_MITSUBA_RESOLUTION = 4096
#: The most samples of one Mitsuba render (samples per pixel × pixels): 16 times those 10 minutes, some hours on two
#: cores (256 samples a pixel at 4096², 4096 at 1024²).
MAX_MITSUBA_SAMPLES = 1 << 32


def environment_bitmap(width: int = 128) -> np.ndarray:
    """The analytic environment of :func:`render_material`, latitude-longitude float32 ``(width/2, width, 3)``.

    The sky of :func:`frenbrdf.render.lighting.environment_radiance` (bluish at the zenith, warm
    at the horizon, a dark ground) and a small bright sun; Mitsuba's envmap convention (+y up, rows from the zenith down, column u
    at the direction (sin 2πu sin θ, cos θ, −cos 2πu sin θ)).
    """
    height = width // 2
    theta = (np.arange(height) + 0.5) / height * np.pi
    phi = (np.arange(width) + 0.5) / width * 2 * np.pi

    def direction(t, p):
        return np.stack(np.broadcast_arrays(np.sin(p) * np.sin(t), np.cos(t), -np.cos(p) * np.sin(t)), axis=-1)

    directions = direction(theta[:, None], phi[None, :])
    image = environment_radiance(directions)  # the metric renderer's sky
    # A sun 50° above the horizon, up and to the right of the camera's view, about 3° in radius.
    sun_theta, sun_phi = np.radians(40.0), np.radians(130.0)
    cos_angle = directions @ direction(sun_theta, sun_phi)
    image += np.where(cos_angle > np.cos(np.radians(3.0)), 40.0, 0.0)[..., None] * np.array([1.0, 0.95, 0.85])
    return image.astype(np.float32)


def scene_dict(bsdf: dict, *, resolution: int = 256, spp: int = 64, scene: str = "sphere") -> dict:
    """The Mitsuba scene of :func:`render_material`: a unit sphere with ``bsdf``.

    A perspective camera on +z, the :func:`environment_bitmap` environment and two
    directional lights, a path tracer of depth 3.
    """
    mi, _ = _import_mitsuba()
    if scene != "sphere":
        raise ValueError(f"unknown scene {scene!r}; available: 'sphere'")
    _check_size(resolution, spp)
    lights = {"key": KEY_LIGHT, "fill": FILL_LIGHT}  # those of the metric renderer (frenbrdf.render.lighting)
    emitters = {name: {"type": "directional", "direction": [-c for c in towards],
                       "irradiance": {"type": "rgb", "value": list(colour)}}
                for name, (towards, colour) in lights.items()}
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},  # Mitsuba splits a large render into passes itself
        "sensor": {
            "type": "perspective",
            "fov": 30.0,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4.5], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": resolution, "height": resolution, "pixel_format": "rgb",
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sphere": {"type": "sphere", "radius": 1.0, "bsdf": bsdf},
        "environment": {"type": "envmap", "bitmap": mi.Bitmap(environment_bitmap())},
        **emitters,
    }


def _check_size(resolution: int, spp: int) -> None:
    if not 1 <= resolution <= MAX_MITSUBA_RESOLUTION or spp < 1:
        raise ValueError(f"resolution must be in 1 … {MAX_MITSUBA_RESOLUTION} (MAX_MITSUBA_RESOLUTION: a Mitsuba render "
                         f"takes about 55 bytes a pixel) and spp ≥ 1, got {resolution} and {spp}")
    if spp * resolution**2 > MAX_MITSUBA_SAMPLES:
        raise ValueError(f"spp {spp} at {resolution}² asks for {spp * resolution**2:,} samples; a Mitsuba render takes "
                         f"at most {MAX_MITSUBA_SAMPLES:,} (MAX_MITSUBA_SAMPLES: some hours on two cores), e.g. "
                         f"spp {MAX_MITSUBA_SAMPLES // resolution**2} at this resolution")


def render_material(material, out_path: str | os.PathLike | None = None, spp: int = 64, resolution: int = 256,
                    scene: str = "sphere", *, seed: int = 0, sampling: str = "fitted",
                    exposure: float = 1.0) -> np.ndarray:
    """Renders a material on a sphere in Mitsuba 3.

    Parameters
    ----------
    material
        A MERL path, an NBRDF, a saved-NBRDF path, a Keras ``.h5`` or a MERL table
        (anything :func:`load_material` takes).
    out_path
        If given, also write a PNG there (atomically): exposure → clamp → gamma 2.2.
    spp, resolution
        Samples per pixel; image width and height.
    scene
        ``"sphere"`` (the only one).
    seed
        The sampler's seed.
    sampling
        ``"fitted"`` importance sampling or ``"cosine"`` only.
    exposure
        Multiplier applied to the PNG only.

    Returns
    -------
    numpy.ndarray
        Linear RGB radiance, float32 ``(resolution, resolution, 3)``.
    """
    _check_size(resolution, spp)  # before the material is read or Mitsuba sizes a tensor
    mi, _ = _import_mitsuba()
    register()
    known = isinstance(material, str) and material in _HANDLES
    handle = material_handle(material)
    try:
        scene_object = mi.load_dict(scene_dict(bsdf_dict(handle, sampling=sampling), resolution=resolution, spp=spp,
                                               scene=scene))
        image = np.array(mi.render(scene_object, spp=spp, seed=seed), dtype=np.float32)
    finally:
        if not known:
            release_handle(handle)
    if out_path is not None:
        save_png(out_path, tonemap(image, exposure))
    return image
