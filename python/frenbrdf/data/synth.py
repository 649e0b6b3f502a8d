"""A seeded bank of physically based analytic BRDFs, written as MERL files.

This is the project's embedded default data: with no measured materials at hand,
:func:`write_bank` produces a folder of real MERL ``.binary`` files (and a ``bank.json``
manifest) from isotropic analytic models whose colours and roughness are spread like
those of the MERL database: many paints and plastics, several metals, a few fabrics and
clear-coated materials, from rough to near-mirror.

The materials come from the analytic families of :mod:`frenbrdf.data.analytic` (models,
formulas, reciprocity and energy conservation are documented there); this module draws
them at random (:func:`material_bank`), names them and writes them
(:func:`write_bank`). The analytic names (``AnalyticMaterial``, ``evaluate``,
``merl_table``, ``METALS``, ...) stay importable from here.

Examples
--------
>>> from frenbrdf import synth
>>> bank = synth.material_bank(100, seed=0)
>>> bank[0].name, bank[0].kind
('synth-000-orange-fabric', 'fabric')
>>> table = synth.merl_table(bank[0])      # (3, 90, 90, 180), −1 × scale where missing
>>> paths = synth.write_bank("bank", n=100)                     # doctest: +SKIP
"""

from __future__ import annotations

import colorsys
import json
import os
from pathlib import Path

import numpy as np

from ..io.atomic import write_text
from ..io.merl import FILE_BYTES, write_merl
from ..io.outputs import OutputFolder, check_free_space
from .analytic import (
    METALS,
    MIN_ROUGHNESS,
    RGB,
    SHEEN_ROUGHNESS_RANGE,
    AnalyticMaterial,
    evaluate,
    merl_table,
)
from .microfacet import ggx_d, ggx_visibility

__all__ = ["DIFFRACTIVE_SHARES", "FAMILY_SHARES", "FEATURE_SHARES", "KINDS", "KIND_SHARES", "MANIFEST_NAME", "MIXES", "METALS", "MIN_ROUGHNESS", "RGB", "SHEEN_ROUGHNESS_RANGE",
           "AnalyticMaterial", "draw_material", "evaluate", "ggx_d", "ggx_visibility", "material_bank", "merl_table", "write_bank"]

#: The kinds of material in the default bank, and the share of each.
KIND_SHARES = {"plastic": 0.35, "metal": 0.25, "coated": 0.20, "fabric": 0.10, "diffuse": 0.10}
KINDS = tuple(KIND_SHARES)

#: The ``features`` mix: what real measurements show and the default bank lacks or holds
#: little of. Car paints (tinted flakes under a clear coat, as in RGL's vch_golden_yellow),
#: retro-reflection (beaded and rough surfaces), thin-film colour shift, grazing sheen
#: (felts) and clear coats over saturated bases.
FEATURE_SHARES = {"carpaint": 0.30, "retroreflective": 0.20, "iridescent": 0.15, "fabric": 0.20, "coated": 0.15}

#: The ``families`` mix: the kinds of the real measurements that no measurement here covers
#: enough (issue 48), modelled on their physics: thin-film iridescence on the coat (Belcour &
#: Barla 2017), interference (pearlescent) pigments whose colour turns with angle under a clear
#: coat (colour-shift paints and wraps), and glitter: sparkles of one hue over a base of another.
FAMILY_SHARES = {"iridescent": 1 / 3, "pearlescent": 1 / 3, "glitter": 1 / 3}

#: The ``diffractive`` mix: flake paints whose flakes carry a grating, rainbows about every highlight (RGL's
#: irid_flake_paint2, which no family above imitates). A mix of its own, so that the ``families`` banks that
#: trained the shipped model stay as they were drawn.
DIFFRACTIVE_SHARES = {"diffractive": 1.0}

#: The banks :func:`material_bank` can draw, by name.
MIXES = {"default": KIND_SHARES, "features": FEATURE_SHARES, "families": FAMILY_SHARES,
         "diffractive": DIFFRACTIVE_SHARES}

#: The manifest written next to the tables by :func:`write_bank`.
MANIFEST_NAME = "bank.json"


# --- The bank ------------------------------------------------------------------------


def _kind_counts(n: int, shares: dict[str, float]) -> dict[str, int]:
    """How many materials of each kind a bank of ``n`` holds.

    ``shares`` rounded by largest remainder; every kind at least once when ``n`` allows it.
    """
    kinds = tuple(shares)
    target = np.array(list(shares.values())) * n
    counts = np.floor(target).astype(int)
    if n >= len(kinds):
        counts = np.maximum(counts, 1)
    while counts.sum() < n:
        counts[np.argmax(target - counts)] += 1
    while counts.sum() > n:  # only after raising small kinds to 1: take from the most over-served
        counts[np.argmax(np.where(counts > 1, counts - target, -np.inf))] -= 1
    return dict(zip(kinds, counts.tolist(), strict=True))


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


def _linear(display_rgb) -> RGB:
    """Display (gamma 2.2) colour → linear reflectance."""
    return tuple(float(c) ** 2.2 for c in display_rgb)


def _paint_colour(rng: np.random.Generator) -> RGB:
    """A paint- or plastic-like albedo: moderate saturation, some dark, some bright."""
    hue = rng.uniform()
    saturation = 0.95 * rng.beta(1.6, 2.2)
    value = rng.uniform(0.08, 0.3) if rng.uniform() < 0.2 else rng.uniform(0.3, 0.95)
    return _linear(colorsys.hsv_to_rgb(hue, saturation, value))


_HUE_NAMES = ((0.04, "red"), (0.11, "orange"), (0.19, "yellow"), (0.45, "green"), (0.54, "cyan"),
              (0.72, "blue"), (0.83, "purple"), (0.95, "pink"), (1.01, "red"))


def _colour_name(rgb: RGB) -> str:
    """A short name for a linear colour, e.g. ``dark-blue`` or ``grey``."""
    hue, saturation, value = colorsys.rgb_to_hsv(*(c ** (1 / 2.2) for c in rgb))
    if saturation < 0.15:
        return "black" if value < 0.2 else "grey" if value < 0.7 else "white"
    name = next(label for bound, label in _HUE_NAMES if hue < bound)
    return f"dark-{name}" if value < 0.35 else name


def _sample_metal(rng: np.random.Generator, roughness_range=(0.01, 0.6)) -> tuple[str, dict]:
    metal = list(METALS)[rng.integers(len(METALS))]
    n, k = METALS[metal]
    params = {"metal_n": n, "metal_k": k, "roughness": _log_uniform(rng, *roughness_range)}
    if rng.uniform() < 0.3:  # a tinted (anodised, lacquered) variant; brightest channel stays 1
        params["tint"] = _linear(colorsys.hsv_to_rgb(rng.uniform(), rng.uniform(0.15, 0.5), 1.0))
        metal = f"tinted-{metal}"
    return metal, params


def _sample_diffuse(rng: np.random.Generator) -> tuple[str, dict]:
    colour = _paint_colour(rng)
    return _colour_name(colour), {"diffuse": colour}


def _sample_plastic(rng: np.random.Generator) -> tuple[str, dict]:
    colour = _paint_colour(rng)
    return _colour_name(colour), {"diffuse": colour, "specular": 1.0,
                                  "roughness": _log_uniform(rng, 0.01, 0.6), "ior": rng.uniform(1.4, 1.7)}


def _sample_fabric(rng: np.random.Generator) -> tuple[str, dict]:
    colour = _paint_colour(rng)
    # The sheen is a paler, brighter version of the cloth's colour.
    hue, saturation, _ = colorsys.rgb_to_hsv(*(c ** (1 / 2.2) for c in colour))
    sheen = _linear(colorsys.hsv_to_rgb(hue, 0.5 * saturation, rng.uniform(0.5, 1.0)))
    return _colour_name(colour), {"diffuse": colour, "sheen": sheen,
                                  "sheen_roughness": rng.uniform(*SHEEN_ROUGHNESS_RANGE)}


def _sample_coated(rng: np.random.Generator) -> tuple[str, dict]:
    coat = {"coat": rng.uniform(0.6, 1.0), "coat_roughness": _log_uniform(rng, 0.01, 0.15),
            "coat_ior": rng.uniform(1.45, 1.6)}
    if rng.uniform() < 0.4:  # metallic paint: a rough metal under the clear coat
        label, base = _sample_metal(rng, roughness_range=(0.15, 0.6))
    else:
        label, base = _sample_diffuse(rng)
    return label, {**base, **coat}


def _saturated_colour(rng: np.random.Generator, hue: float, saturation=(0.5, 0.95), value=(0.15, 0.75)) -> RGB:
    return _linear(colorsys.hsv_to_rgb(hue % 1.0, rng.uniform(*saturation), rng.uniform(*value)))


def _clear_coat(rng: np.random.Generator) -> dict:
    return {"coat": rng.uniform(0.8, 1.0), "coat_roughness": _log_uniform(rng, 0.005, 0.05),
            "coat_ior": rng.uniform(1.45, 1.6)}


def _flake_paint(rng: np.random.Generator, hue_offset, saturation, share, roughness) -> tuple[str, dict]:
    """A saturated base (darker than paints) under metallic flakes tinted a hue ``hue_offset(rng)`` turns
    away, covering a share ``share`` of it, GGX-spread over ``roughness``, under a glossy clear coat."""
    hue = rng.uniform()
    colour = _saturated_colour(rng, hue, value=(0.05, 0.6))
    flakes = _linear(colorsys.hsv_to_rgb((hue + hue_offset(rng)) % 1.0, rng.uniform(*saturation), 1.0))
    return _colour_name(colour), {"diffuse": colour, "flakes": rng.uniform(*share), "flake_colour": flakes,
                                  "flake_roughness": _log_uniform(rng, *roughness), **_clear_coat(rng)}


def _sample_carpaint(rng: np.random.Generator) -> tuple[str, dict]:
    # Flakes of a nearby, paler hue: RGL's vch_golden_yellow is a dark golden base under broad, strongly
    # yellow flake highlights.
    return _flake_paint(rng, lambda r: r.normal(0.0, 0.04), (0.3, 1.0), (0.2, 0.8), (0.08, 0.4))


def _sample_retroreflective(rng: np.random.Generator) -> tuple[str, dict]:
    colour = _paint_colour(rng)
    # The retro lobe's colour: the surface's own hue, paler (light that never entered deeply).
    hue, saturation, _ = colorsys.rgb_to_hsv(*(c ** (1 / 2.2) for c in colour))
    retro = tuple(rng.uniform(0.05, 0.35) * c for c in _linear(colorsys.hsv_to_rgb(hue, 0.5 * saturation, 1.0)))
    params = {"diffuse": colour, "retro": retro, "retro_roughness": _log_uniform(rng, 0.1, 0.6)}
    if rng.uniform() < 0.5:
        params |= {"specular": 1.0, "roughness": _log_uniform(rng, 0.05, 0.6), "ior": rng.uniform(1.4, 1.6)}
    return _colour_name(colour), params


def _sample_iridescent(rng: np.random.Generator) -> tuple[str, dict]:
    # A thin film (soap, oxide, pearlescent lacquer) on the coat over a dark base or a metal.
    if rng.uniform() < 0.35:
        label, base = _sample_metal(rng, roughness_range=(0.15, 0.6))
    else:
        base = {"diffuse": _saturated_colour(rng, rng.uniform(), saturation=(0.0, 0.9), value=(0.02, 0.4))}
        label = _colour_name(base["diffuse"])
    film = {"film_thickness": rng.uniform(150.0, 900.0), "film_ior": rng.uniform(1.3, 2.2)}
    return label, {**base, **_clear_coat(rng), "coat_roughness": _log_uniform(rng, 0.01, 0.15), **film}


def _sample_pearlescent(rng: np.random.Generator) -> tuple[str, dict]:
    # Mica flakes under a titanium-dioxide film over a darker base, under a clear coat: the flakes'
    # interference colour turns with angle (RGL's colour-shift wraps: a mauve base, cyan highlights).
    base = _saturated_colour(rng, rng.uniform(), saturation=(0.2, 0.9), value=(0.03, 0.45))
    flakes = {"flakes": rng.uniform(0.3, 0.9), "flake_film_thickness": rng.uniform(150.0, 700.0),
              "flake_film_ior": rng.uniform(2.2, 2.7), "flake_roughness": _log_uniform(rng, 0.05, 0.4)}
    return _colour_name(base), {"diffuse": base, **flakes, **_clear_coat(rng)}


def _sample_glitter(rng: np.random.Generator) -> tuple[str, dict]:
    # Narrow, saturated sparkles of a hue far from the base's (RGL's vch_dragon_eye_red, vch_ultra_pink).
    return _flake_paint(rng, lambda r: r.uniform(0.2, 0.8), (0.6, 1.0), (0.1, 0.5), (0.02, 0.15))


def _sample_diffractive(rng: np.random.Generator) -> tuple[str, dict]:
    # Aluminium flakes carrying a grating of 500–2,000 lines/mm (holographic pigments) over a dark, mostly greyish
    # base under a clear coat; the flakes tilt little, so their rings stay sharp.
    base = _saturated_colour(rng, rng.uniform(), saturation=(0.0, 0.6), value=(0.03, 0.35))
    flakes = {"flakes": rng.uniform(0.2, 0.7), "flake_roughness": _log_uniform(rng, 0.02, 0.15),
              "flake_grating": _log_uniform(rng, 500.0, 2000.0), "flake_grating_efficiency": rng.uniform(0.1, 0.6)}
    return _colour_name(base), {"diffuse": base, **flakes, **_clear_coat(rng)}


_SAMPLERS = {"diffuse": _sample_diffuse, "plastic": _sample_plastic, "metal": _sample_metal,
             "fabric": _sample_fabric, "coated": _sample_coated, "carpaint": _sample_carpaint,
             "retroreflective": _sample_retroreflective, "iridescent": _sample_iridescent,
             "pearlescent": _sample_pearlescent, "glitter": _sample_glitter, "diffractive": _sample_diffractive}


def draw_material(rng: np.random.Generator, kind: str | None = None, name: str = "{label}-{kind}") -> AnalyticMaterial:
    """One random analytic material, drawn as the bank draws them.

    Parameters
    ----------
    rng
        The source of every random choice (colours, roughness, Fresnel, layers).
    kind
        A kind of :data:`MIXES` (e.g. ``"carpaint"``); None draws it with the probabilities of
        :data:`KIND_SHARES`.
    name
        The material's name, a template in which ``{label}`` (e.g. ``copper``) and ``{kind}``
        are filled in.
    """
    if kind is None:
        kind = KINDS[rng.choice(len(KINDS), p=np.array(list(KIND_SHARES.values())))]
    if kind not in _SAMPLERS:
        raise ValueError(f"kind must be one of {tuple(_SAMPLERS)}, got {kind!r}")
    label, params = _SAMPLERS[kind](rng)
    return AnalyticMaterial(name=name.format(label=label, kind=kind), **params)


#: The most materials a bank holds (each MERL file is 35 MB: 10,000 of them are 350 GB).
MAX_BANK = 10_000


def check_bank_size(n) -> None:
    """Refuses a bank size outside 1 … :data:`MAX_BANK` before anything is drawn."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= MAX_BANK:
        raise ValueError(f"a material bank holds 1 … {MAX_BANK:,} materials, got {n!r}")


def material_bank(n: int = 100, seed: int = 0, mix: str = "default") -> list[AnalyticMaterial]:
    """A deterministic bank of ``n`` analytic materials.

    Kinds follow the shares of ``MIXES[mix]`` (:data:`KIND_SHARES` by default; every kind
    appears once ``n`` is at least the number of kinds) in a shuffled order; colours,
    roughness and the other parameters are drawn from ``numpy.random.default_rng(seed)``.
    Names look like ``synth-007-copper-metal``, or ``features-006-dark-green-carpaint`` in
    the ``features`` mix.

    Raises
    ------
    ValueError
        ``n`` outside 1 … :data:`MAX_BANK`, or a ``mix`` not in :data:`MIXES`.
    """
    check_bank_size(n)
    if mix not in MIXES:
        raise ValueError(f"mix must be one of {tuple(MIXES)}, got {mix!r}")
    rng = np.random.default_rng(seed)
    kinds = [kind for kind, count in _kind_counts(n, MIXES[mix]).items() for _ in range(count)]
    prefix = "synth" if mix == "default" else mix  # two mixes can share a training folder
    width = max(3, len(str(n - 1)))
    bank = []
    for index, kind in enumerate(rng.permutation(kinds)):
        bank.append(draw_material(rng, str(kind), name=f"{prefix}-{index:0{width}d}-{{label}}-{{kind}}"))
    return bank


def write_bank(out_dir: str | os.PathLike, n: int = 100, seed: int = 0, *, mix: str = "default",
               overwrite: bool = False, progress: bool = True) -> list[Path]:
    """Writes :func:`material_bank` ``(n, seed, mix)`` as MERL files and a manifest.

    Each material becomes ``out_dir / f"{name}.binary"``; ``out_dir / "bank.json"`` records
    ``n``, ``seed``, ``mix`` and every material's parameters. The folder follows the output rule of
    :mod:`frenbrdf.io.outputs`: an earlier bank there is replaced, never mixed with this one; a folder
    holding anything else is refused unless ``overwrite`` (the user's entries are then kept). The size
    and the free disk space are checked before anything is drawn.

    Parameters
    ----------
    out_dir
        Destination folder: new, empty, or an earlier bank.
    n, seed, mix
        Passed to :func:`material_bank`.
    overwrite
        Write into ``out_dir`` even if it holds entries that are not an earlier bank's (they are kept).
    progress
        Show a progress bar.

    Returns
    -------
    list of pathlib.Path
        The MERL files, in bank order.

    Raises
    ------
    ValueError
        ``n`` outside 1 … :data:`MAX_BANK`, an unknown ``mix``, or an ``out_dir`` that holds other entries
        (without ``overwrite``).
    OSError
        Not enough free disk space.
    """
    from tqdm import tqdm

    check_bank_size(n)
    out = OutputFolder.claim(out_dir, command="synth", overwrite=overwrite, option="out_dir")
    check_free_space(out.target, n * FILE_BYTES, f"{n} MERL files")
    bank = material_bank(n, seed, mix)
    names = [f"{material.name}.binary" for material in bank]
    out.check_names([*names, MANIFEST_NAME])
    with out.staged() as staging:
        for material, name in zip(tqdm(bank, desc="synthesising BRDFs", unit="material", disable=not progress),
                                  names, strict=True):
            write_merl(staging / name, merl_table(material))
        manifest = {"n": n, "seed": seed, "mix": mix,
                    "materials": [{"file": name, **m.to_dict()} for name, m in zip(names, bank, strict=True)]}
        write_text(staging / MANIFEST_NAME, json.dumps(manifest, indent=2) + "\n")
    return [out.path / name for name in names]
