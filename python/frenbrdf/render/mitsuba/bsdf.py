"""The ``frenbrdf`` BSDF class: evaluation by :class:`Kernels`, sampling by the fitted mixture."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

from .kernels import Kernels
from .material import _HANDLES, _load_file
from .sampling import COSINE_ONLY
from .variants import PLUGIN_NAME, _import_mitsuba, set_variant


@functools.cache
def bsdf_class(variant: str):
    """The plugin class for a variant (Mitsuba's BSDF base class differs per variant)."""
    mi, dr = _import_mitsuba()
    if mi.variant() != variant:
        raise RuntimeError(f"the Mitsuba variant is {mi.variant()!r}, expected {variant!r}")
    BSDF: Any = mi.BSDF  # the variant's base class, known only at run time

    class FreNBRDFBSDF(BSDF):
        """A MERL table, measurement or NBRDF as a Mitsuba BSDF (see :mod:`frenbrdf.render.mitsuba`)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            filename = props.get("filename", None)
            handle = props.get("material", None)
            lookup = str(props.get("lookup", "trilinear"))
            sampling = str(props.get("sampling", "fitted"))
            if (filename is None) == (handle is None):
                raise ValueError("the frenbrdf BSDF needs exactly one of 'filename' (a MERL file, RGL .bsdf, saved "
                                 "NBRDF or Keras .h5) and 'material' (a handle from "
                                 "frenbrdf.render.mitsuba.material_handle)")
            if handle is not None and handle not in _HANDLES:
                raise ValueError(f"unknown material handle {handle!r}: create it with "
                                 "frenbrdf.render.mitsuba.material_handle() in this process")
            if lookup not in ("trilinear", "nearest"):
                raise ValueError(f"lookup must be 'trilinear' or 'nearest', got {lookup!r}")
            if sampling not in ("fitted", "cosine"):
                raise ValueError(f"sampling must be 'fitted' or 'cosine', got {sampling!r}")
            self.material = _HANDLES[handle] if handle is not None else _load_file(Path(filename))
            self.kernels = Kernels(mi, dr, self.material, lookup)
            self.mixture = self.material.sampling if sampling == "fitted" else COSINE_ONLY
            self.distributions = [mi.MicrofacetDistribution(mi.MicrofacetType.GGX, lobe.alpha, True)
                                  for lobe in self.mixture.lobes]
            flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def _brdf(self, wi, wo, active):
            """f at a pair as Mitsuba passes it: ``si.wi`` towards the camera, ``wo`` towards the light. The order
            matters only to an ordered NBRDF or a measurement, which take the light's direction first (as the
            metric renderer does)."""
            return self.kernels(wo, wi, active) if self.material.ordered else self.kernels(wi, wo, active)

        def _pdf(self, wi, wo, active):
            pdf = self.mixture.cosine * mi.warp.square_to_cosine_hemisphere_pdf(wo)
            if self.mixture.lobes:
                m = dr.normalize(wi + wo)
                jacobian = dr.rcp(dr.maximum(4.0 * dr.dot(wo, m), 1e-20))
                for lobe, distribution in zip(self.mixture.lobes, self.distributions, strict=True):
                    pdf += lobe.weight * distribution.pdf(wi, m) * jacobian
            return dr.select(active, pdf, 0.0)

        def _active(self, ctx, si, wo, active):
            enabled = ctx.is_enabled(mi.BSDFFlags.GlossyReflection)
            cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
            return active & (cos_i > 0) & (cos_o > 0) & enabled, cos_o

        def eval(self, ctx, si, wo, active=True):
            active, cos_o = self._active(ctx, si, wo, active)
            return dr.select(active, self._brdf(si.wi, wo, active) * cos_o, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            active, _ = self._active(ctx, si, wo, active)
            return self._pdf(si.wi, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            active, cos_o = self._active(ctx, si, wo, active)
            value = dr.select(active, self._brdf(si.wi, wo, active) * cos_o, 0.0)
            return value, self._pdf(si.wi, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = si.wi
            active = active & (mi.Frame3f.cos_theta(wi) > 0) & ctx.is_enabled(mi.BSDFFlags.GlossyReflection)
            wo = mi.warp.square_to_cosine_hemisphere(sample2)
            threshold = self.mixture.cosine
            for lobe, distribution in zip(self.mixture.lobes, self.distributions, strict=True):
                m, _ = distribution.sample(wi, sample2)
                wo = dr.select(sample1 >= threshold, mi.reflect(wi, m), wo)
                threshold += lobe.weight
            cos_o = mi.Frame3f.cos_theta(wo)
            active &= cos_o > 0
            pdf = self._pdf(wi, wo, active)
            active &= pdf > 0
            value = self._brdf(wi, wo, active) * cos_o
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = wo
            bs.pdf = pdf
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            weight = dr.select(active, value / dr.maximum(pdf, 1e-30), 0.0)
            return bs, weight

        def traverse(self, callback):
            pass

        def to_string(self):
            lobes = ", ".join(f"GGX α={lobe.alpha:.3g} p={lobe.weight:.2f}" for lobe in self.mixture.lobes)
            return (f"FreNBRDF[{self.material.kind} {self.material.name!r}, "
                    f"sampling: cosine p={self.mixture.cosine:.2f}{', ' + lobes if lobes else ''}]")

    return FreNBRDFBSDF


_REGISTERED: set[str] = set()


def register() -> str:
    """Registers the ``"frenbrdf"`` BSDF plugin with Mitsuba and returns the variant.

    Selects a variant first (:func:`set_variant`) if none is set. Registration is per
    variant: call again after switching variants. Calling twice is harmless.
    """
    mi, _ = _import_mitsuba()
    variant = set_variant()
    if variant not in _REGISTERED:
        cls = bsdf_class(variant)
        mi.register_bsdf(PLUGIN_NAME, lambda props: cls(props))
        _REGISTERED.add(variant)
    return variant
