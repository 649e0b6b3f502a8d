"""The Mitsuba 3 plugin: Dr.Jit evaluation equals numpy, sampling is consistent, renders work.

Needs the ``mitsuba`` extra (``pip install -e ".[test]"`` installs it); the tests that run
Mitsuba skip without it. Most also need the ``llvm_ad_rgb`` variant (in ``scalar_rgb`` a
Python BSDF runs one ray at a time, far too slowly for them): Dr.Jit's LLVM backend uses
the system's libLLVM when it works, else the one the extra installs (karellen-llvm-core),
so the tests fail, rather than skip, when neither works.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf.data.analytic import METALS, AnalyticMaterial, merl_table
from frenbrdf.io import write_material
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.models.nbrdf import NBRDF, NBRDFConfig, fold_difference
from frenbrdf.render import mitsuba as fm

from .conftest import HAVE_MITSUBA, mitsuba_jit

needs_mitsuba = pytest.mark.skipif(not HAVE_MITSUBA, reason="mitsuba is not installed (pip install mitsuba)")


@pytest.fixture(scope="module")
def mi():
    """Mitsuba with the plugin registered, in a JIT variant."""
    return mitsuba_jit()


def tiny_nbrdf(seed: int = 0, hidden=(8, 8), reference=None) -> NBRDF:
    generator = torch.Generator().manual_seed(seed)
    params = [torch.randn(1, *shape, generator=generator) * 0.5 for shape in NBRDFConfig(hidden).shapes()]
    return NBRDF(params, LogRelativeMapping(np.full(3, 0.1) if reference is None else reference))


@pytest.fixture(scope="module")
def gold_table() -> np.ndarray:
    """A GGX gold metal (α = 0.1) as a MERL table."""
    n, k = METALS["gold"]
    return merl_table(AnalyticMaterial("gold", metal_n=n, metal_k=k, roughness=0.1))


@pytest.fixture(scope="module")
def plastic_table() -> np.ndarray:
    """A rough plastic (Lambert + GGX α = 0.2), used as a per-bin reference BRDF."""
    return merl_table(AnalyticMaterial("plastic", diffuse=(0.4, 0.2, 0.1), specular=1.0, roughness=0.2))


def float32(v: np.ndarray) -> np.ndarray:
    """Directions as Mitsuba receives them (float32), in float64 for the numpy reference.

    Near θ_h = 0 the azimuth of H, and with it D, moves by ~1e-4 under float32 rounding
    of the directions: references are computed at the rounded directions.
    """
    return np.asarray(v, dtype=np.float32).astype(np.float64)


def upper_hemisphere(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 1e-3
    return float32(v / np.linalg.norm(v, axis=1, keepdims=True))


def interaction(mi, wi: np.ndarray):
    import drjit as dr

    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T, dtype=np.float32))
    return si


def mitsuba_eval(mi, bsdf, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The plugin's eval (f · cos θ_o) at pairs, ``(n, 3)``."""
    value = bsdf.eval(mi.BSDFContext(), interaction(mi, wi), mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32)))
    return np.array(value).T


def assert_close(got: np.ndarray, expected: np.ndarray, rtol: float = 1e-4):
    """Relative agreement, with an absolute floor far below the material's values."""
    floor = 1e-5 * np.abs(expected).max()
    error = np.abs(got - expected) / (np.abs(expected) + floor)
    worst = np.unravel_index(error.argmax(), error.shape)
    assert error.max() < rtol, f"max relative error {error.max():.2e} at {worst}"


def assert_nbrdf_close(got: np.ndarray, expected: np.ndarray, wi: np.ndarray, wo: np.ndarray, per_bin: bool = False):
    """1e-4 relative, except within 0.01 rad of θ_h = 0 and, with a per-bin reference, at its steps.

    Near θ_h = 0 H's azimuth, and with it D's, is ill-conditioned: float32 arithmetic on
    ω_i + ω_o moves it by ~1e-4 rad at θ_h = 1e-4, and an NBRDF with random weights
    (unlike a physical BRDF) depends on φ_d at θ_h = 0. Those pairs get 1e-2. A per-bin
    reference steps from 0 to its value over one bin where MERL's missing bins begin, so
    float32 bin coordinates (~3e-5 bins off) cost up to ~1e-3 on the few pairs there.
    """
    near_pole = frenbrdf.directions_to_rusinkiewicz(wi, wo)[:, 0] < 0.01
    assert near_pole.sum() < 0.01 * len(wi)
    if per_bin:
        floor = 1e-5 * np.abs(expected).max()
        error = (np.abs(got - expected) / (np.abs(expected) + floor))[~near_pole]
        assert np.quantile(error, 0.999) < 1e-4 and error.max() < 1e-3, (np.quantile(error, 0.999), error.max())
    else:
        assert_close(got[~near_pole], expected[~near_pole])
    if near_pole.any():
        assert_close(got[near_pole], expected[near_pole], rtol=1e-2)


# --------------------------------------------------------------------------- eval


@pytest.mark.parametrize("per_bin", [False, True], ids=["per-channel-reference", "per-bin-reference"])
def test_nbrdf_eval_equals_numpy(mi, plastic_table, per_bin):
    nbrdf = tiny_nbrdf(reference=np.maximum(plastic_table, 0.0) if per_bin else None)
    bsdf = mi.load_dict(fm.bsdf_dict(nbrdf))
    rng = np.random.default_rng(1)
    wi, wo = upper_hemisphere(rng, 20000), upper_hemisphere(rng, 20000)
    expected = nbrdf(wi, wo) * wo[:, 2:3]
    assert expected.max() > 0 and np.mean(expected > 0) > 0.5
    assert_nbrdf_close(mitsuba_eval(mi, bsdf, wi, wo), expected, wi, wo, per_bin)


def test_nbrdf_eval_uses_the_training_convention_phi_h_zero(mi):
    """The network sees H = (sin θ_h, 0, cos θ_h), whatever the pair's φ_h (isotropy), and D folded
    onto D_y ≥ 0 (reciprocity), as frenbrdf.models.nbrdf.nbrdf_coordinates gives them."""
    nbrdf = tiny_nbrdf(seed=3)
    bsdf = mi.load_dict(fm.bsdf_dict(nbrdf))
    rng = np.random.default_rng(2)
    n = 20000
    angles = np.stack([rng.uniform(0, 1.2, n), rng.uniform(-np.pi, np.pi, n), rng.uniform(0, 1.2, n),
                       rng.uniform(-np.pi, np.pi, n)], axis=-1)
    wi, wo = (float32(v) for v in frenbrdf.rusinkiewicz_to_directions(angles))
    keep = (wi[:, 2] > 0.01) & (wo[:, 2] > 0.01)
    wi, wo = wi[keep], wo[keep]
    angles = frenbrdf.directions_to_rusinkiewicz(wi, wo)
    assert np.ptp(angles[:, 1]) > 6  # pairs of every φ_h …
    h, d = frenbrdf.rusinkiewicz_to_half_diff(angles * [1, 0, 1, 1])  # … evaluated at φ_h = 0
    expected = nbrdf.mapping.inverse(nbrdf.mapped(np.concatenate([h, fold_difference(d)], axis=-1)), 0.1) * wo[:, 2:3]
    assert_nbrdf_close(mitsuba_eval(mi, bsdf, wi, wo), expected, wi, wo)


def test_an_ordered_nbrdf_takes_the_light_first(mi):
    """Mitsuba's si.wi points to the camera and wo to the light; an ordered NBRDF (one that tells the two orders of a
    pair apart, as a refined measurement may) is evaluated as f(light, camera), as the metric renderer does."""
    ordered = tiny_nbrdf(seed=5)
    ordered.ordered = True
    bsdf = mi.load_dict(fm.bsdf_dict(ordered))
    rng = np.random.default_rng(4)
    camera, light = upper_hemisphere(rng, 20000), upper_hemisphere(rng, 20000)
    expected = ordered(light, camera) * light[:, 2:3]
    assert np.median(np.abs(ordered(camera, light) - ordered(light, camera))) > 0.01 * np.median(expected)  # it can fail
    assert_nbrdf_close(mitsuba_eval(mi, bsdf, camera, light), expected, light, camera)


def test_keras_h5_file_eval_equals_the_reference(mi, tmp_path):
    """A Keras .h5 read by the plugin (frenbrdf.io.read_material) evaluates as its NBRDF (the reference forward pass)."""
    from frenbrdf.data.nbrdf_import import keras_nbrdf

    from .conftest import random_layers, write_keras_h5

    layers = [(k.astype(np.float32).astype(np.float64), b.astype(np.float32).astype(np.float64))
              for k, b in random_layers([6, 8, 8, 3], seed=9)]
    bsdf = mi.load_dict(fm.bsdf_dict(write_keras_h5(tmp_path / "keras.h5", layers)))
    rng = np.random.default_rng(4)
    wi, wo = upper_hemisphere(rng, 20000), upper_hemisphere(rng, 20000)
    expected = keras_nbrdf(layers)(wi, wo) * wo[:, 2:3]
    assert expected.max() > 0
    # exp(y) − 1 in float32 cancels where the output is near 0 (as the mapping's f_ref = 0
    # makes it): 1e-3 relative there, against 1e-4 for a mapping with f_ref > 0.
    near_pole = frenbrdf.directions_to_rusinkiewicz(wi, wo)[:, 0] < 0.01
    assert_close(mitsuba_eval(mi, bsdf, wi, wo)[~near_pole], expected[~near_pole], rtol=1e-3)


@pytest.mark.parametrize("method", ["trilinear", "nearest"])
def test_merl_eval_equals_native_lookup(mi, gold_table, method):
    bsdf = mi.load_dict(fm.bsdf_dict(gold_table, lookup=method))
    rng = np.random.default_rng(4)
    wi, wo = upper_hemisphere(rng, 20000), upper_hemisphere(rng, 20000)
    expected = np.maximum(frenbrdf.merl_lookup_directions(gold_table, wi, wo, method=method), 0.0) * wo[:, 2:3]
    got = mitsuba_eval(mi, bsdf, wi, wo)
    if method == "trilinear":
        assert_close(got, expected)
    else:
        # float32 angles may round to the neighbouring bin right at a bin boundary.
        floor = 1e-5 * expected.max()
        agree = np.all(np.abs(got - expected) <= 1e-4 * (np.abs(expected) + floor), axis=-1)
        assert agree.mean() > 0.999, agree.mean()


def test_merl_eval_skips_missing_bins(mi):
    """Corners without a measurement are left out; no measured corner gives 0."""
    table = np.full((3, 90, 90, 180), 0.5)
    table[:, :, 45:, :] = -1.0  # θ_d ≥ 45°: missing
    bsdf = mi.load_dict(fm.bsdf_dict(table))
    rng = np.random.default_rng(5)
    wi, wo = upper_hemisphere(rng, 5000), upper_hemisphere(rng, 5000)
    theta_d = frenbrdf.directions_to_rusinkiewicz(wi, wo)[:, 2]
    got = mitsuba_eval(mi, bsdf, wi, wo) / wo[:, 2:3]
    assert np.allclose(got[theta_d < np.radians(44.9)], 0.5, rtol=1e-5)
    assert np.all(got[theta_d > np.radians(45.1)] == 0)


def test_eval_is_zero_below_the_horizon(mi, gold_table):
    bsdf = mi.load_dict(fm.bsdf_dict(tiny_nbrdf()))
    rng = np.random.default_rng(6)
    wi, wo = upper_hemisphere(rng, 1000), upper_hemisphere(rng, 1000)
    below = wo * [1, 1, -1]
    assert np.all(mitsuba_eval(mi, bsdf, wi, below) == 0)
    assert np.all(mitsuba_eval(mi, bsdf, below, wo) == 0)
    assert np.all(np.isfinite(mitsuba_eval(mi, bsdf, wi, wo)))


# --------------------------------------------------------------------------- sampling


def test_fitted_lobe_recovers_ggx_roughness(gold_table):
    mixture = fm.fit_sampling(fm.material_from_table(gold_table).brdf)
    main = max(mixture.lobes, key=lambda lobe: lobe.weight)
    assert 0.07 < main.alpha < 0.15, mixture
    assert mixture.cosine == pytest.approx(fm.MIN_COSINE_WEIGHT), mixture  # a metal: no Lambert term
    lambert = fm.fit_sampling(lambda wi, wo: np.full(np.shape(wi), 0.2))
    assert lambert == fm.COSINE_ONLY


@pytest.mark.parametrize("material", ["gold", "nbrdf"])
@pytest.mark.parametrize("incidence", [0.0, 1.2])
def test_sample_weight_is_eval_over_pdf(mi, gold_table, material, incidence):
    bsdf = mi.load_dict(fm.bsdf_dict(gold_table if material == "gold" else tiny_nbrdf()))
    n = 50000
    rng = np.random.default_rng(7)
    wi = np.tile([np.sin(incidence), 0.0, np.cos(incidence)], (n, 1))
    si, ctx = interaction(mi, wi), mi.BSDFContext()
    bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n, dtype=np.float32)),
                             mi.Point2f(rng.random((2, n), dtype=np.float32)))
    value, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    weight, value, pdf, sampled_pdf = np.array(weight).T, np.array(value).T, np.array(pdf), np.array(bs.pdf)
    ok = sampled_pdf > 0
    assert ok.mean() > 0.9
    assert np.allclose(sampled_pdf[ok], pdf[ok], rtol=1e-5)
    assert np.allclose(np.array(bsdf.pdf(ctx, si, bs.wo))[ok], pdf[ok], rtol=1e-5)
    assert_close(weight[ok], value[ok] / pdf[ok][:, None], rtol=1e-5)
    assert np.all(weight[~ok] == 0) and np.all(np.isfinite(weight))
    assert np.all(np.array(bs.wo)[2][ok] > 0)
    if material == "gold":
        # Good importance sampling of a GGX metal: weights stay near its albedo (≤ 1).
        assert weight.max() < 1.5


@pytest.mark.parametrize("incidence", [0.0, 0.7, 1.3])
def test_pdf_integrates_to_one_over_the_hemisphere(mi, gold_table, incidence):
    """∫ pdf dω over the upper hemisphere (MC) ≈ the share of samples that stay above it, ≈ 1."""
    bsdf = mi.load_dict(fm.bsdf_dict(gold_table))
    n = 1 << 21
    rng = np.random.default_rng(8)
    u = rng.random((n, 2))
    z, phi = u[:, 0], 2 * np.pi * u[:, 1]
    wo = np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], axis=-1)
    wi = np.tile([np.sin(incidence), 0.0, np.cos(incidence)], (n, 1))
    si, ctx = interaction(mi, wi), mi.BSDFContext()
    pdf = np.array(bsdf.pdf(ctx, si, mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32))), dtype=np.float64)
    integral, error = 2 * np.pi * pdf.mean(), 2 * np.pi * pdf.std() / np.sqrt(n)
    bs, _ = bsdf.sample(ctx, si, mi.Float(rng.random(n, dtype=np.float32)),
                        mi.Point2f(rng.random((2, n), dtype=np.float32)))
    kept = np.mean(np.array(bs.pdf) > 0)
    assert integral == pytest.approx(kept, abs=4 * error + 4 * np.sqrt(kept * (1 - kept) / n))
    assert 0.9 < integral < 1 + 4 * error


def test_sampling_passes_a_chi2_test(mi, gold_table):
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    for incidence in (0.0, 1.0):
        wi = mi.ScalarVector3f(float(np.sin(incidence)), 0.0, float(np.cos(incidence)))
        sample, pdf = BSDFAdapter(fm.PLUGIN_NAME, fm.bsdf_dict(gold_table), wi=wi)
        test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=3,
                             res=101, ires=16)
        assert test.run(significance_level=0.01, quiet=True), test.messages


# --------------------------------------------------------------------------- rendering


def test_render_small_sphere_from_files(mi, gold_table, tmp_path):
    """A saved NBRDF and a MERL file render to finite, non-black images; the PNG is written."""
    nbrdf_path, merl_path, png = tmp_path / "tiny.pt", tmp_path / "gold.binary", tmp_path / "gold.png"
    handles = dict(fm._HANDLES)
    write_material(nbrdf_path, tiny_nbrdf().weights())
    frenbrdf.write_merl(merl_path, gold_table)
    for path, out in ((nbrdf_path, None), (merl_path, png)):
        image = fm.render_material(path, out, spp=16, resolution=32)
        assert image.shape == (32, 32, 3) and image.dtype == np.float32
        assert np.all(np.isfinite(image)) and image.mean() > 0.01
        assert image[16, 16].max() > 0  # the sphere's centre is lit
    assert png.stat().st_size > 0 and sorted(p.name for p in tmp_path.iterdir()) == ["gold.binary", "gold.png",
                                                                                     "tiny.pt"]
    assert fm._HANDLES == handles  # render_material released what it registered


def test_render_cli_accepts_a_saved_nbrdf(mi, tmp_path, capsys):
    """`frenbrdf render x.pt --mitsuba` (the file fit-nbrdf writes) gives the PNG of the NBRDF's Mitsuba render."""
    import matplotlib.image

    from frenbrdf.cli import main

    nbrdf, path, png = tiny_nbrdf(seed=5), tmp_path / "material.pt", tmp_path / "material.png"
    write_material(path, nbrdf.weights())
    assert main(["render", str(path), "--mitsuba", "--out", str(png), "--resolution", "16", "--spp", "4"]) == 0
    assert "wrote" in capsys.readouterr().out
    written = matplotlib.image.imread(png)[..., :3]
    expected = fm.tonemap(fm.render_material(nbrdf, spp=4, resolution=16))
    assert written.shape == (16, 16, 3) and expected[8, 8].max() > 0
    np.testing.assert_allclose(written, expected, atol=1 / 255 + 1e-6)  # 8-bit PNG


def test_importance_sampling_beats_cosine_sampling(mi, gold_table):
    reference = fm.tonemap(fm.render_material(gold_table, spp=256, resolution=24, seed=1))
    errors = {sampling: np.sqrt(np.mean((fm.tonemap(fm.render_material(gold_table, spp=16, resolution=24,
                                                                         sampling=sampling)) - reference) ** 2))
              for sampling in ("fitted", "cosine")}
    assert errors["fitted"] < 0.5 * errors["cosine"], errors


# --------------------------------------------------------------------------- errors, fallback


def test_plugin_refuses_bad_properties(mi, tmp_path):
    with pytest.raises(Exception, match="exactly one of 'filename'"):
        mi.load_dict({"type": fm.PLUGIN_NAME})
    with pytest.raises(Exception, match="unknown material handle"):
        mi.load_dict({"type": fm.PLUGIN_NAME, "material": "no-such-handle"})
    with pytest.raises(Exception, match="lookup must be"):
        mi.load_dict(fm.bsdf_dict(tiny_nbrdf(), lookup="cubic"))
    (tmp_path / "junk.bin").write_bytes(b"not a material")
    with pytest.raises(ValueError, match=r"junk.bin: read_material reads \.binary .*; this file has the suffix"):
        fm.load_material(tmp_path / "junk.bin")
    with pytest.raises(FileNotFoundError):
        fm.load_material(tmp_path / "missing.binary")
    with pytest.raises(ValueError, match="holds 2 materials"):
        fm.load_material(NBRDF([torch.cat([p, p]) for p in tiny_nbrdf().params], LogRelativeMapping(np.ones(3))))
    with pytest.raises(ValueError, match="unknown scene"):
        fm.render_material(tiny_nbrdf(), scene="cornell-box")
    with pytest.raises(ValueError, match="resolution must be in 1 … 4096"):  # before Mitsuba sizes a tensor
        fm.render_material(tiny_nbrdf(), resolution=50_000, spp=1)


def test_missing_mitsuba_raises_an_import_error_naming_pip(monkeypatch):
    monkeypatch.setitem(sys.modules, "mitsuba", None)
    with pytest.raises(ImportError, match="pip install mitsuba"):
        fm.set_variant()
    with pytest.raises(ImportError, match="pip install mitsuba"):
        fm.render_material(tiny_nbrdf())


@needs_mitsuba
def test_scalar_fallback_when_llvm_is_unusable(tmp_path):
    """Without a usable libLLVM: a warning, scalar_rgb, and a plugin that still agrees with numpy."""
    script = textwrap.dedent("""
        import warnings
        import numpy as np, torch
        from frenbrdf import mitsuba as fm
        from frenbrdf.models.mapping import LogRelativeMapping
        from frenbrdf.models.nbrdf import NBRDF, NBRDFConfig, fold_difference
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            variant = fm.register()
        assert variant == "scalar_rgb", variant
        assert any("falling back to scalar_rgb" in str(w.message) for w in caught), [str(w.message) for w in caught]
        import mitsuba as mi
        g = torch.Generator().manual_seed(0)
        nbrdf = NBRDF([torch.randn(1, *s, generator=g) * 0.5 for s in NBRDFConfig((4,)).shapes()],
                      LogRelativeMapping(np.full(3, 0.1)))
        bsdf = mi.load_dict(fm.bsdf_dict(nbrdf))
        si = mi.SurfaceInteraction3f()
        for wi, wo in (([0.3, 0.1, 0.9], [-0.2, 0.4, 0.8]), ([0.8, 0.0, 0.6], [-0.6, 0.0, 0.8])):
            wi, wo = np.array(wi) / np.linalg.norm(wi), np.array(wo) / np.linalg.norm(wo)
            si.wi = mi.ScalarVector3f(*wi)
            got = np.array(bsdf.eval(mi.BSDFContext(), si, mi.ScalarVector3f(*wo)))
            expected = nbrdf(wi, wo) * wo[2]
            assert np.allclose(got, expected, rtol=1e-4), (got, expected)
        image = fm.render_material(nbrdf, spp=1, resolution=4)
        assert np.all(np.isfinite(image)) and image.max() > 0
        print("ok")
    """)
    env = {**os.environ, "DRJIT_LIBLLVM_PATH": str(tmp_path / "no-libLLVM.so")}
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=300)
    assert result.returncode == 0 and result.stdout.strip().endswith("ok"), result.stdout + result.stderr


# --------------------------------------------------------------------------- which libLLVM


def test_packaged_llvm_is_chosen_only_when_the_system_has_none(monkeypatch):
    """DRJIT_LIBLLVM_PATH → the pip package's libLLVM only when unset, drjit not yet imported and the system's fails."""
    from frenbrdf.render.mitsuba import variants

    system_works = {"value": True}
    monkeypatch.setattr(variants, "packaged_libllvm", lambda: "/site/lib/libLLVM.so.19.1")
    monkeypatch.setattr(variants, "_llvm_works", lambda libllvm: libllvm is not None or system_works["value"])
    monkeypatch.delitem(sys.modules, "drjit", raising=False)
    monkeypatch.delenv(fm.LIBLLVM_VARIABLE, raising=False)
    assert variants.use_packaged_llvm() is None and fm.LIBLLVM_VARIABLE not in os.environ  # the system's works
    system_works["value"] = False
    monkeypatch.setitem(sys.modules, "drjit", object())
    assert variants.use_packaged_llvm() is None and fm.LIBLLVM_VARIABLE not in os.environ  # too late: imported
    monkeypatch.delitem(sys.modules, "drjit")
    monkeypatch.setenv(fm.LIBLLVM_VARIABLE, "/mine/libLLVM.so")
    assert variants.use_packaged_llvm() == "/mine/libLLVM.so" == os.environ[fm.LIBLLVM_VARIABLE]  # the user's
    monkeypatch.delenv(fm.LIBLLVM_VARIABLE)
    assert variants.use_packaged_llvm() == "/site/lib/libLLVM.so.19.1" == os.environ[fm.LIBLLVM_VARIABLE]
    monkeypatch.setattr(variants, "packaged_libllvm", lambda: None)
    monkeypatch.delenv(fm.LIBLLVM_VARIABLE)
    assert variants.use_packaged_llvm() is None and fm.LIBLLVM_VARIABLE not in os.environ  # nothing to point at


@needs_mitsuba
def test_packaged_libllvm_runs_the_llvm_variant():
    """The libLLVM the test extras install works in Dr.Jit: llvm_ad_rgb renders with the plugin (whatever the system has)."""
    packaged = fm.packaged_libllvm()
    if packaged is None:
        pytest.skip(f"{fm.LLVM_PACKAGE} is not installed (pip install -e '.[test]' installs it on Linux x86-64)")
    script = textwrap.dedent("""
        import numpy as np, drjit as dr
        from frenbrdf import mitsuba as fm
        from frenbrdf.data.analytic import AnalyticMaterial, merl_table
        assert fm.register() == "llvm_ad_rgb"
        image = fm.render_material(merl_table(AnalyticMaterial("grey", diffuse=(0.5, 0.5, 0.5))), spp=2, resolution=8)
        assert np.all(np.isfinite(image)) and image[4, 4].max() > 0
        print("llvm", *dr.detail.llvm_version())
    """)
    env = {**os.environ, fm.LIBLLVM_VARIABLE: packaged}
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=300)
    assert result.returncode == 0 and result.stdout.strip().startswith("llvm 19 "), result.stdout + result.stderr
