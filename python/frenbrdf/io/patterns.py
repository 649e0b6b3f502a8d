"""Sampling patterns: the (ω_i, ω_o) pairs a kind of device measures, by name (:data:`PATTERNS`).

An encoder reads a material from the samples it is given, and real instruments do not sample alike: a
gonioreflectometer sweeps a detector through the plane of incidence at a few incidence angles, a camera and a few
lights see many pairs near the mirror and back-scatter directions and none elsewhere, a user copying values out
of a paper has an in-plane slice. Each pattern is a function ``pattern(count, rng) -> (wi, wo)``: exactly
``count`` pairs, each direction a float64 ``(count, 3)`` unit vector in the local frame (z the normal) strictly
above the surface (z > 0), the same for the same state of ``rng`` (a :class:`numpy.random.Generator`). A
device's setup (its lights, its camera, the sample's turn about its normal) is drawn anew at each call, so many
calls imitate many devices of the kind. docs/usage.md ("Sampling patterns") draws each in Rusinkiewicz
coordinates (``docs/patterns/make_pictures.py``).

:func:`sample_pattern` draws a pattern by name; :func:`measure` evaluates a whole material (a MERL table through
:func:`~frenbrdf.io.merl.merl_lookup_directions`, a ``.bsdf`` measurement itself) at a pattern's pairs, as
:func:`frenbrdf.io.read_samples` does with ``pattern=``. ``merl-bins`` is what the models have been given so
far, and stays the default everywhere.

Examples
--------
>>> import numpy as np
>>> from frenbrdf.io.patterns import sample_pattern
>>> wi, wo = sample_pattern("gonioreflectometer", 1000, np.random.default_rng(0))
>>> wi.shape, bool((wi[:, 2] > 0).all() and (wo[:, 2] > 0).all())
((1000, 3), True)
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..numerics.coords import rusinkiewicz_to_directions
from .merl import merl_lookup_directions
from .samples import MAX_SAMPLES, Measurements
from .sampling import _above_horizon, as_table, bin_directions, sample_bins, truth_samples

#: The counts a device gives, from a few hundred gonioreflectometer readings to a dense image-based capture: the
#: range the patterns are meant for (:func:`sample_pattern` takes 1 … :data:`~frenbrdf.io.samples.MAX_SAMPLES`).
SENSIBLE_COUNTS = (50, 20_000)
#: The largest polar angle a pattern aims at on purpose (a detector's sweep, a drawn θ): 85°.
MOST = math.radians(85)
#: The incidence angles of :func:`gonioreflectometer` by default.
INCIDENCE = tuple(math.radians(a) for a in (0, 20, 40, 60, 75))
#: Rounds of drawing again (pairs below the horizon, a table's unmeasured bins) before a pattern gives up.
_ROUNDS = 60

Pairs = tuple[np.ndarray, np.ndarray]


def _directions(theta, phi) -> np.ndarray:
    """Unit vectors ``(..., 3)`` at polar angles ``theta`` and azimuths ``phi``."""
    sin = np.sin(theta)
    return np.stack([sin * np.cos(phi), sin * np.sin(phi), np.cos(theta)], axis=-1)


def _turned(v: np.ndarray, phi) -> np.ndarray:
    """``v`` ``(..., 3)`` turned about the normal (z) by ``phi``."""
    cos, sin = np.cos(phi), np.sin(phi)
    return np.stack([cos * v[..., 0] - sin * v[..., 1], sin * v[..., 0] + cos * v[..., 1], v[..., 2]], axis=-1)


def _on_the_sample(wi: np.ndarray, wo: np.ndarray, rng: np.random.Generator) -> Pairs:
    """The pairs of one setup with the sample turned about its normal by one random azimuth (an isotropic material
    does not depend on it; the pairs do not all share one plane)."""
    phi = rng.uniform(0, 2 * np.pi)
    return _turned(wi, phi), _turned(wo, phi)


def _rayleigh(n: int, width: float, rng: np.random.Generator) -> np.ndarray:
    """Angles from a Rayleigh distribution of scale ``width`` (the polar angle of a 2-D Gaussian spot), cut at
    4 × ``width``."""
    return width * np.sqrt(-2 * np.log1p(-rng.random(n) * (1 - math.exp(-8))))


def _filled(draw: Callable[[int, np.random.Generator], Pairs], count: int, rng: np.random.Generator,
            what: str) -> Pairs:
    """``count`` pairs of ``draw(n, rng)`` whose directions both lie strictly above the surface, drawn in rounds
    until there are enough (each round sized by the share the last one kept)."""
    kept_i, kept_o, have, share = [np.empty((0, 3))], [np.empty((0, 3))], 0, 0.5
    for _ in range(_ROUNDS):
        if have >= count:
            break
        wi, wo = draw(int((count - have) / max(share, 0.02) * 1.2) + 16, rng)
        keep = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        share = keep.mean()
        kept_i.append(wi[keep])
        kept_o.append(wo[keep])
        have += int(keep.sum())
    if have < count:
        raise RuntimeError(f"{what}: found {have} of {count} pairs above the horizon in {_ROUNDS} rounds")
    return np.concatenate(kept_i)[:count], np.concatenate(kept_o)[:count]


def _spread(count: int, parts: int) -> list[int]:
    """``count`` split into ``parts`` shares as even as can be (the first ones one larger)."""
    return [count // parts + (i < count % parts) for i in range(parts)]


def merl_bins(count: int, rng: np.random.Generator) -> Pairs:
    """Random MERL bins above the horizon, without replacement, at each bin's pair (φ_h = 0): what the models
    have been given so far, and what a whole material is sampled at by default. Uniform over the bins, so dense
    at small θ_h (MERL's θ_h bins are spaced quadratically) and uniform in θ_d and φ_d ∈ [0, π). :func:`measure`
    draws a material's own measured bins instead (:func:`frenbrdf.io.sampling.sample_bins`)."""
    bins = np.flatnonzero(_above_horizon())
    if count > len(bins):
        raise ValueError(f"merl-bins draws each bin at most once: at most {len(bins):,} pairs, asked for {count:,}")
    return bin_directions(rng.choice(bins, size=count, replace=False))


def _hemisphere(n: int, rng: np.random.Generator, *, cosine: bool) -> np.ndarray:
    """``n`` directions uniform over the hemisphere (by solid angle: cos θ uniform), or cosine-weighted (cos θ the
    square root of a uniform number); never on the horizon."""
    z = 1 - rng.random(n)  # (0, 1]
    z = np.sqrt(z) if cosine else z
    phi = rng.uniform(0, 2 * np.pi, n)
    radius = np.sqrt(np.maximum(1 - z * z, 0))
    return np.stack([radius * np.cos(phi), radius * np.sin(phi), z], axis=-1)


def uniform(count: int, rng: np.random.Generator) -> Pairs:
    """ω_i and ω_o each uniform over the hemisphere (by solid angle), independently. No device samples this way:
    every configuration alike, most of them far from the specular peak (θ_h mostly large), half of the
    directions beyond 60°."""
    return _hemisphere(count, rng, cosine=False), _hemisphere(count, rng, cosine=False)


def cosine(count: int, rng: np.random.Generator) -> Pairs:
    """ω_i and ω_o each cosine-weighted over the hemisphere (density ∝ cos θ), independently: the pairs that carry
    the most light, the way a renderer importance-samples a diffuse surface; few near grazing."""
    return _hemisphere(count, rng, cosine=True), _hemisphere(count, rng, cosine=True)


def in_plane(count: int, rng: np.random.Generator) -> Pairs:
    """ω_o in the plane of incidence (the plane of ω_i and the normal), on either side: θ_i uniform in 0–85°, the
    detector's signed angle uniform in −85…85° (positive on the mirror side), the plane at a random azimuth; so
    φ_o − φ_i is 0 or π. What a paper's in-plane plot gives a user who copies values off it; nothing out of plane."""
    theta_i, signed = rng.uniform(0, MOST, count), rng.uniform(-MOST, MOST, count)
    wi = _directions(theta_i, np.zeros(count))
    wo = np.stack([-np.sin(signed), np.zeros(count), np.cos(signed)], axis=-1)
    return _on_the_sample(wi, wo, rng)


def _sweep(n: int, source: float, gap: float) -> np.ndarray:
    """``n`` detector positions (signed angles in the plane of incidence) at regular steps over −85…85°, skipping
    ``gap`` about the source's position ``source``, where the detector would block the light."""
    low, high = max(source - gap / 2, -MOST), min(source + gap / 2, MOST)
    steps = np.linspace(0, 2 * MOST - (high - low), n)
    positions = -MOST + steps
    return np.where(positions >= low, positions + (high - low), positions)


def gonioreflectometer(count: int, rng: np.random.Generator, *, incidence: tuple[float, ...] = INCIDENCE,
                       in_plane: float = 0.7, jitter: float = math.radians(0.25)) -> Pairs:
    """A gonioreflectometer: the source at a few incidence angles (``incidence``, radians; 0°, 20°, 40°, 60° and
    75° by default), the count spread evenly over them. For ``in_plane`` of each angle's pairs the detector is
    swept at regular steps through the plane of incidence (−85…85°, skipping 5° about the source, which it would
    block); for the rest along two arcs across that plane, through the mirror direction and through the normal
    (±85° each). Every angle of the device is off by up to ±``jitter`` (its repeatability: uniform, 0.25° by
    default), the detector's azimuth too; the sample at a random azimuth. In Rusinkiewicz coordinates: a few
    curves, one per incidence angle, dense along them."""
    wis, wos = [], []
    for theta, n in zip(incidence, _spread(count, len(incidence)), strict=True):
        plane = round(in_plane * n)
        mirror = (n - plane + 1) // 2
        signed = _sweep(plane, -theta, math.radians(5)) + rng.uniform(-jitter, jitter, plane)
        swept = _turned(np.stack([-np.sin(signed), np.zeros(plane), np.cos(signed)], axis=-1),
                        rng.uniform(-jitter, jitter, plane))
        beta = np.linspace(-MOST, MOST, mirror) + rng.uniform(-jitter, jitter, mirror)
        across_mirror = np.stack([-np.sin(theta) * np.cos(beta), np.sin(beta), np.cos(theta) * np.cos(beta)], axis=-1)
        beta = np.linspace(-MOST, MOST, n - plane - mirror) + rng.uniform(-jitter, jitter, n - plane - mirror)
        across_normal = np.stack([np.zeros(len(beta)), np.sin(beta), np.cos(beta)], axis=-1)
        source = theta + rng.uniform(-jitter, jitter, n)
        wis.append(np.stack([np.sin(source), np.zeros(n), np.cos(source)], axis=-1))
        wos.append(np.concatenate([swept, across_mirror, across_normal]))
    return _on_the_sample(np.concatenate(wis), np.concatenate(wos), rng)


def _frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents ``(..., 3)`` completing each normal (z ≥ 0) to an orthonormal frame (Duff et al. 2017)."""
    x, y, z = normals[..., 0], normals[..., 1], normals[..., 2]
    a = -1 / (1 + z)
    b = x * y * a
    return (np.stack([1 + x * x * a, b, -x], axis=-1), np.stack([b, 1 + y * y * a, -y], axis=-1))


def _local(direction: np.ndarray, normals: np.ndarray, tangent: np.ndarray, bitangent: np.ndarray) -> np.ndarray:
    """``direction`` (one, or one per row) in the frame of each row's normal: ``(n, 3)``."""
    return np.stack([(direction * tangent).sum(-1), (direction * bitangent).sum(-1), (direction * normals).sum(-1)],
                    axis=-1)


def image_based(count: int, rng: np.random.Generator, *, lights: int | None = None,
                spread: float = math.radians(135)) -> Pairs:
    """Photographs of a sphere of the material: a camera far away and ``lights`` point lights far away (1–8,
    drawn when None) at random directions up to ``spread`` from the camera's, the count spread evenly over them.
    Each pixel of the sphere's image (drawn uniformly over the disk it covers) has its own normal; its pair is the
    light's and the camera's direction in that normal's frame, kept where both are above the surface there. θ_d
    is half the angle between the light and the camera, the same at every pixel: one line of constant θ_d per
    light, θ_h running out from 0 (the pixel that mirrors the light into the camera). What an image-based
    measurement (Marschner et al. 1999; Matusik et al. 2003) takes from one photograph per light."""
    lights = int(rng.integers(1, 9)) if lights is None else lights
    camera = np.array([0.0, 0.0, 1.0])
    towards = _directions(np.arccos(rng.uniform(math.cos(spread), 1, lights)), rng.uniform(0, 2 * np.pi, lights))
    wis, wos = [], []
    for light, n in zip(towards, _spread(count, lights), strict=True):
        def pixels(m: int, rng: np.random.Generator, light=light) -> Pairs:
            radius, angle = np.sqrt(rng.random(m)), rng.uniform(0, 2 * np.pi, m)
            normals = np.stack([radius * np.cos(angle), radius * np.sin(angle), np.sqrt(1 - radius ** 2)], axis=-1)
            frame = _frames(normals)
            return _local(light, normals, *frame), _local(camera, normals, *frame)

        wi, wo = _filled(pixels, n, rng, "image-based")
        wis.append(wi)
        wos.append(wo)
    return np.concatenate(wis), np.concatenate(wos)


def flat_sample(count: int, rng: np.random.Generator, *, lights: int | None = None) -> Pairs:
    """Photographs of a flat swatch of the material: a pinhole camera 3 swatch widths from its centre, at a polar
    angle drawn in 0–60°, and ``lights`` point lights (1–4, drawn when None) 2–4 widths away, the first within
    10° of the camera's mirror direction (so the photograph holds the highlight), the others anywhere up to 80°
    from the normal; the count spread evenly over the lights. Each pixel (a point drawn uniformly over the swatch)
    has its own light and view directions: each light gives a small patch of pairs, a few degrees across. A phone
    photograph of a swatch, or a few of them."""
    lights = int(rng.integers(1, 5)) if lights is None else lights
    theta_c, phi_c = rng.uniform(0, math.radians(60)), rng.uniform(0, 2 * np.pi)
    camera = 3 * _directions(theta_c, phi_c)
    mirror = _directions(theta_c, phi_c + np.pi)
    near = _directions(np.arccos(rng.uniform(math.cos(math.radians(10)), 1)), rng.uniform(0, 2 * np.pi))
    first = near @ np.stack([*_frames(mirror), mirror])  # within 10° of the mirror direction
    others = _directions(np.arccos(rng.uniform(math.cos(math.radians(80)), 1, lights - 1)),
                         rng.uniform(0, 2 * np.pi, lights - 1))
    positions = rng.uniform(2, 4, (lights, 1)) * np.concatenate([first[None], others])
    wis, wos = [], []
    for light, n in zip(positions, _spread(count, lights), strict=True):
        points = np.concatenate([rng.uniform(-0.5, 0.5, (n, 2)), np.zeros((n, 1))], axis=1)
        wi, wo = light - points, camera - points
        wis.append(wi / np.linalg.norm(wi, axis=-1, keepdims=True))
        wos.append(wo / np.linalg.norm(wo, axis=-1, keepdims=True))
    return np.concatenate(wis), np.concatenate(wos)


def _from_angles(theta_h, theta_d, rng: np.random.Generator) -> Pairs:
    """Pairs at these θ_h, θ_d, with φ_h and φ_d uniform."""
    n = len(theta_h)
    angles = np.stack([theta_h, rng.uniform(0, 2 * np.pi, n), theta_d, rng.uniform(0, 2 * np.pi, n)], axis=-1)
    return rusinkiewicz_to_directions(angles)


def specular(count: int, rng: np.random.Generator, *, width: float = math.radians(5)) -> Pairs:
    """Around the mirror direction only: θ_h from a Rayleigh distribution of scale ``width`` (the half vector a
    Gaussian spot about the normal; 5° by default) cut at 4 × ``width``, θ_d uniform in 0–85°, φ_h and φ_d uniform;
    pairs below the horizon drawn again. A device aimed at the highlight, or the highlight pixels of photographs."""
    return _filled(lambda n, rng: _from_angles(_rayleigh(n, width, rng), rng.uniform(0, MOST, n), rng),
                   count, rng, "specular")


def back_scatter(count: int, rng: np.random.Generator, *, width: float = math.radians(5)) -> Pairs:
    """Around the back-scatter (retro-reflection) direction only, ω_o near ω_i: θ_d from a Rayleigh distribution
    of scale ``width`` (5° by default) cut at 4 × ``width``, θ_h uniform in 0–85°, φ_h and φ_d uniform; pairs
    below the horizon drawn again. A camera with its flash beside it (a phone), or a retro-reflectometer."""
    return _filled(lambda n, rng: _from_angles(rng.uniform(0, MOST, n), _rayleigh(n, width, rng), rng),
                   count, rng, "back-scatter")


def peaks(count: int, rng: np.random.Generator) -> Pairs:
    """Half :func:`specular` (the extra one when odd), half :func:`back-scatter <back_scatter>`, in a random
    order: the two peaks a camera and lights see most of, and nothing between them."""
    wi_s, wo_s = specular(count - count // 2, rng)
    wi_b, wo_b = back_scatter(count // 2, rng)
    order = rng.permutation(count)
    return np.concatenate([wi_s, wi_b])[order], np.concatenate([wo_s, wo_b])[order]


@dataclass(frozen=True)
class Pattern:
    """A named sampling pattern: a function ``(count, rng) -> (wi, wo)`` and the device it imitates."""

    name: str
    """Its name, as ``--pattern`` takes it."""
    draw: Callable[[int, np.random.Generator], Pairs]
    """``(count, rng) -> (wi, wo)``: see the module docstring."""
    imitates: str
    """The device, in a few words."""

    def __call__(self, count: int, rng: np.random.Generator) -> Pairs:
        return self.draw(count, rng)


#: Every sampling pattern, by name; ``merl-bins`` first, the default.
PATTERNS = {entry.name: entry for entry in (
    Pattern("merl-bins", merl_bins, "what the models have been given so far: random bins of a MERL table"),
    Pattern("uniform", uniform, "no device: every configuration alike"),
    Pattern("cosine", cosine, "no device: the configurations that carry the most light"),
    Pattern("in-plane", in_plane, "values copied off a paper's in-plane plot"),
    Pattern("gonioreflectometer", gonioreflectometer,
            "a gonioreflectometer: a few incidence angles, the detector swept in and across the plane of incidence"),
    Pattern("image-based", image_based, "photographs of a sphere of the material under 1–8 point lights"),
    Pattern("flat-sample", flat_sample, "photographs of a flat swatch under 1–4 point lights"),
    Pattern("specular", specular, "a device aimed at the highlight"),
    Pattern("back-scatter", back_scatter, "a camera with its flash beside it"),
    Pattern("peaks", peaks, "the highlight and the back-scatter, nothing between"),
)}
#: The default pattern: today's sampling of a whole material.
DEFAULT = "merl-bins"


def pattern(name: str) -> Pattern:
    """The pattern called ``name``; a ValueError naming the patterns for any other name."""
    if name not in PATTERNS:
        raise ValueError(f"unknown sampling pattern {name!r}; the patterns are {', '.join(PATTERNS)}")
    return PATTERNS[name]


def _checked_count(count) -> int:
    if (isinstance(count, bool) or not isinstance(count, numbers.Integral)
            or not 1 <= int(count) <= MAX_SAMPLES):
        low, high = SENSIBLE_COUNTS
        raise ValueError(f"a pattern's count must be a whole number in 1 … {MAX_SAMPLES:,} (devices give "
                         f"{low} … {high:,}), got {count!r}")
    return int(count)


def sample_pattern(name: str, count: int, rng: np.random.Generator) -> Pairs:
    """``count`` pairs ``(wi, wo)`` of the pattern ``name`` (:data:`PATTERNS`), drawn from ``rng``.

    Raises
    ------
    ValueError
        An unknown name, or a count that is not a whole number in 1 … :data:`~frenbrdf.io.samples.MAX_SAMPLES`
        (devices give :data:`SENSIBLE_COUNTS`: 50 … 20,000).
    """
    return pattern(name)(_checked_count(count), rng)


def pattern_samples(truth, name: str, count: int, rng: np.random.Generator, *,
                    table: np.ndarray | None = None) -> tuple[np.ndarray, Pairs]:
    """A whole material's reflectance ``(N, 3)`` at ``count`` pairs of the pattern ``name`` and the pairs
    ``(wi, wo)``: what an encoder takes (as :func:`~frenbrdf.io.sampling.truth_samples` gives).

    ``truth``: a MERL table, looked up trilinearly (:func:`~frenbrdf.io.merl.merl_lookup_directions`; a pair
    where the table holds no measurement is drawn again), or a measurement called at the pairs in the pattern's
    order (values below 0 raised to 0). ``merl-bins`` draws the material's own measured bins as
    :func:`frenbrdf.io.sampling.draw_samples` does (the same values from the same ``rng``; a count beyond them
    is capped at all of them) and a measurement's order of each pair; ``table``: the material's table when at
    hand (:func:`~frenbrdf.io.sampling.as_table`). Raises as :func:`sample_pattern`, and a ValueError when a table
    holds a measurement at too few of the pattern's pairs.
    """
    draw = pattern(name)
    count = _checked_count(count)
    if name == "merl-bins":
        return truth_samples(truth, sample_bins(as_table(truth) if table is None else table, rng, count), rng)
    if not isinstance(truth, np.ndarray):
        wi, wo = draw(count, rng)
        return np.maximum(truth(wi, wo), 0.0), (wi, wo)
    values, wis, wos, have = [], [], [], 0
    for _ in range(_ROUNDS):
        wi, wo = draw(count - have, rng)
        found = merl_lookup_directions(truth, wi, wo)
        keep = np.all(found >= 0, axis=-1)
        values.append(found[keep])
        wis.append(wi[keep])
        wos.append(wo[keep])
        have += int(keep.sum())
        if have == count:
            return np.concatenate(values), (np.concatenate(wis), np.concatenate(wos))
    raise ValueError(f"the table holds a measurement at {have} of {count} pairs drawn by {name!r} in {_ROUNDS} "
                     "rounds: too few where the pattern samples")


def measure(material, name: str, count: int, rng: np.random.Generator, *, source: str = "") -> Measurements:
    """A whole material (a MERL table, or a measurement such as :class:`~frenbrdf.io.bsdf.MeasuredBSDF`)
    measured at ``count`` pairs of the pattern ``name`` (:func:`pattern_samples`), as
    :class:`~frenbrdf.io.samples.Measurements` with the material kept as the truth to render (as
    :func:`frenbrdf.io.read_samples` returns it). ``source``: the file, for the result and for messages."""
    try:
        table = as_table(material)
        values, (wi, wo) = pattern_samples(material, name, count, rng, table=table)
    except ValueError as error:
        raise ValueError(f"{source}: {error}" if source else str(error)) from None
    kind = "merl" if isinstance(material, np.ndarray) else "bsdf"
    return Measurements(np.array(values, dtype=np.float64), wi, wo, source, kind, table, material)
