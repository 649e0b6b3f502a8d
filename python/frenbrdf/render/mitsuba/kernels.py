"""The BRDF as Dr.Jit kernels: NBRDF layers unrolled with constant weights, trilinear MERL gathers, and
measurements evaluated by Mitsuba's own ``measured`` BSDF."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from ...io.bsdf import HORIZON
from ...models.nbrdf import SEAM
from .material import Material


class Kernels:
    """The BRDF in Dr.Jit for the current variant: ``f(wi, wo)`` (no cosine), RGB."""

    def __init__(self, mi, dr, material: Material, lookup: str):
        self.mi, self.dr = mi, dr
        self.material = material
        self.lookup = lookup
        self.jit = dr.is_jit_v(mi.Float)
        self.buffer: Any = None  # the table: a Dr.Jit Float (JIT variants) or a numpy array
        if material.kind == "merl" or (material.reference is not None and material.reference.ndim == 4):
            data = material.interleaved
            self.buffer = mi.Float(data.reshape(-1)) if self.jit else data
        if material.kind == "nbrdf":
            self.layers = [(w.astype(np.float64).tolist(), b.astype(np.float64).tolist())
                           for w, b in material.layers]
        if material.measurement is not None:  # kind "measured"
            # Mitsuba's `measured` plugin reads the same file: the Dupuy & Jakob evaluation, in Dr.Jit, agrees
            # with the Rust core's to float32 precision (tests/io/test_bsdf_native.py).
            self.measured = mi.load_dict({"type": "measured", "filename": str(material.measurement.path)})

    # -- geometry

    def half_diff(self, wi, wo):
        """H and D (frenbrdf.half_diff_vectors) of unit or non-unit directions."""
        mi, dr = self.mi, self.dr
        wi, wo = dr.normalize(wi), dr.normalize(wo)
        s = wi + wo
        norm = dr.norm(s)
        h = dr.select(norm > 1e-12, s * dr.rcp(dr.maximum(norm, 1e-30)), mi.Vector3f(0, 0, 1))
        rho = dr.sqrt(dr.fma(h.x, h.x, h.y * h.y))
        pole = rho <= 0
        inv = dr.rcp(dr.maximum(rho, 1e-30))
        cos_t = dr.select(pole, dr.select(h.z < 0, -1.0, 1.0), h.z)
        sin_t = dr.select(pole, 0.0, rho)
        cos_p = dr.select(pole, 1.0, h.x * inv)
        sin_p = dr.select(pole, 0.0, h.y * inv)
        x = dr.fma(cos_p, wi.x, sin_p * wi.y)
        y = dr.fma(-sin_p, wi.x, cos_p * wi.y)
        d = mi.Vector3f(dr.fma(cos_t, x, -sin_t * wi.z), y, dr.fma(sin_t, x, cos_t * wi.z))
        return h, d

    def bin_coordinates(self, h, d):
        """Continuous MERL bin coordinates (θ_h, θ_d, φ_d indices) of H and D."""
        dr = self.dr
        half_pi = np.pi / 2
        theta_h = dr.atan2(dr.sqrt(dr.fma(h.x, h.x, h.y * h.y)), h.z)
        theta_d = dr.atan2(dr.sqrt(dr.fma(d.x, d.x, d.y * d.y)), d.z)
        phi_d = dr.atan2(d.y, d.x)
        i = dr.sqrt(dr.clip(theta_h, 0.0, half_pi) / half_pi) * 90.0
        j = dr.clip(theta_d, 0.0, half_pi) / half_pi * 90.0
        phi_d = dr.select(phi_d < 0, phi_d + np.pi, phi_d)
        k = phi_d / np.pi * 180.0
        k = dr.select(k >= 180.0, k - 180.0, k)
        return i, j, dr.clip(k, 0.0, 179.99998)

    def gather(self, bins, active):
        mi, dr = self.mi, self.dr
        if self.jit:
            return dr.gather(mi.Color3f, self.buffer, bins, active)
        return mi.Color3f(*(float(v) for v in self.buffer[int(bins)]))

    def table_lookup(self, i, j, k, active, method: str, masked: bool):
        """Trilinear (or nearest) lookup in the buffer; corners with negative values left out."""
        mi, dr = self.mi, self.dr
        UInt = mi.UInt32
        if method == "nearest":
            bins = (UInt(dr.minimum(dr.round(i), 89.0)) * 90 + UInt(dr.minimum(dr.round(j), 89.0))) * 180 \
                + UInt(dr.round(k)) % 180
            value = self.gather(bins, active)
            return dr.select(value >= 0, value, 0.0) if masked else value
        axes = []
        for x, n in ((i, 90), (j, 90)):
            x = dr.minimum(x, float(n - 1))
            lo = dr.floor(x)
            lo_i = UInt(lo)
            axes.append(((lo_i, 1.0 - (x - lo)), (dr.minimum(lo_i + 1, n - 1), x - lo)))
        k0 = dr.floor(k)
        k0_i = UInt(k0) % 180
        axes.append(((k0_i, 1.0 - (k - k0)), ((k0_i + 1) % 180, k - k0)))
        total = dr.zeros(mi.Color3f) if self.jit else mi.Color3f(0.0)
        weights = dr.zeros(mi.Color3f) if self.jit else mi.Color3f(0.0)
        for (bi, wi), (bj, wj), (bk, wk) in itertools.product(*axes):
            weight = wi * wj * wk
            value = self.gather((bi * 90 + bj) * 180 + bk, active)
            if masked:
                valid = value >= 0
                total += dr.select(valid, weight * value, 0.0)
                weights += dr.select(valid, weight, 0.0)
            else:
                total += weight * value
        if not masked:
            return total
        return dr.select(weights > 0, total / dr.maximum(weights, 1e-30), 0.0)

    # -- the BRDF

    def mlp(self, h, d):
        """The NBRDF's network at (H, D) with φ_h = 0: mapped RGB (three floats)."""
        dr = self.dr
        # The network was trained on H = (sin θ_h, 0, cos θ_h) and D_y ≥ 0: drop H's azimuth
        # (isotropy) and fold D by reciprocity, as frenbrdf.models.nbrdf.nbrdf_coordinates does. An ordered
        # NBRDF reads the pair's order (+1 unfolded, −1 folded) in H_y's place, which is 0 otherwise.
        flip = (d.y < -SEAM) | ((dr.abs(d.y) <= SEAM) & (d.x < -SEAM))
        order = dr.select(flip, -1.0, 1.0) if self.material.ordered else None
        x = [dr.sqrt(dr.fma(h.x, h.x, h.y * h.y)), order, h.z, dr.select(flip, -d.x, d.x), dr.abs(d.y), d.z]
        last = len(self.layers) - 1
        for index, (weight, bias) in enumerate(self.layers):
            out = []
            for row, b in zip(weight, bias, strict=True):
                acc = None
                for w, xi in zip(row, x, strict=True):
                    if w == 0.0 or xi is None:
                        continue
                    acc = xi * w + b if acc is None else dr.fma(xi, w, acc)
                if acc is None:
                    acc = x[0] * 0.0 + b
                out.append(dr.maximum(acc, 0.0) if index < last else acc)
            x = out
        return x

    def measurement(self, wi, wo, active):
        """A measurement's f(wi, wo) ≥ 0: `measured` returns f · cos θ_o, negative measured values included."""
        mi, dr = self.mi, self.dr
        wi, wo = dr.normalize(wi), dr.normalize(wo)
        si = dr.zeros(mi.SurfaceInteraction3f, dr.width(wi))
        si.wi = wi
        projected = self.measured.eval(mi.BSDFContext(), si, wo, active)
        above = (wi.z > HORIZON) & (wo.z > HORIZON)  # as the Rust reader: on the horizon but for rounding is on it
        return dr.select(active & above, dr.maximum(projected, 0.0) / dr.maximum(wo.z, HORIZON), 0.0)

    def __call__(self, wi, wo, active):
        """Reflectance f(wi, wo) ≥ 0, RGB; meaningful where ``active``."""
        mi, dr = self.mi, self.dr
        if self.material.kind == "measured":
            return self.measurement(wi, wo, active)
        h, d = self.half_diff(wi, wo)
        if self.material.kind == "merl":
            i, j, k = self.bin_coordinates(h, d)
            return self.table_lookup(i, j, k, active, self.lookup, masked=True)
        y = mi.Color3f(*self.mlp(h, d))
        eps = self.material.epsilon
        if self.buffer is None:  # f_ref a constant (3,)
            assert self.material.reference is not None
            reference = mi.Color3f(*(float(r) + eps for r in self.material.reference))
        else:
            i, j, k = self.bin_coordinates(h, d)
            reference = dr.maximum(self.table_lookup(i, j, k, active, "trilinear", masked=False), 0.0) + eps
        return dr.maximum(dr.fma(reference, dr.exp(y) - self.material.offset, -eps), 0.0)

