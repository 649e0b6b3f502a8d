"""The native reader and evaluator of RGL ``.bsdf`` files (Dupuy & Jakob 2018).

Agreement with Mitsuba 3's ``measured`` plugin (``scalar_rgb``; its JIT variants crash on
these files) on the four materials in ``../shared/data/rgl-measured``, and clean errors on
bad files, which are built here with a small numpy writer of the ``tensor_file`` format.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from frenbrdf._native import BsdfMeasurement
from frenbrdf.exceptions import BsdfFormatError

from ..conftest import HAVE_MITSUBA, SHARED_DATA

RGL_DIR = SHARED_DATA / "rgl-measured"
RGL_NAMES = ["acrylic_felt_green_rgb", "cg_sunflower_rgb", "paper_white_rgb", "vch_golden_yellow_rgb"]
#: Direction pairs compared with Mitsuba per file.
N_PAIRS = 20_000

DTYPE_CODES = {np.dtype(t): code for code, t in enumerate(
    ["u1", "i1", "<u2", "<i2", "<u4", "<i4", "<u8", "<i8", "<f2", "<f4", "<f8"], start=1)}


def rgl_file(name: str) -> Path:
    path = RGL_DIR / f"{name}.bsdf"
    if not path.is_file():
        pytest.skip(f"RGL measured material {path.name} not found in {RGL_DIR} (set FRENBRDF_SHARED_DATA)")
    return path


def tensor_file(fields: dict[str, np.ndarray], version: bytes = b"\x01\x00", magic: bytes = b"tensor_file\0") -> bytes:
    """The bytes of a ``tensor_file`` holding ``fields``, each field's data 8-byte aligned."""
    arrays = {name: np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<")) for name, a in fields.items()}
    header_len = 18 + sum(2 + len(name) + 2 + 1 + 8 + 8 * a.ndim for name, a in arrays.items())
    offset = -(-header_len // 8) * 8
    header, data = [magic, version, struct.pack("<I", len(arrays))], []
    for name, a in arrays.items():
        code = DTYPE_CODES[a.dtype.newbyteorder("=") if a.dtype.itemsize > 1 else a.dtype]
        header += [struct.pack("<H", len(name)), name.encode(), struct.pack("<HBQ", a.ndim, code, offset),
                   struct.pack(f"<{a.ndim}Q", *a.shape)]
        data.append(a.tobytes() + b"\0" * (-a.nbytes % 8))
        offset += len(data[-1])
    head = b"".join(header)
    return head + b"\0" * (-len(head) % 8) + b"".join(data)


def flat_material(colour=(0.2, 0.5, 0.7), ndf=2.0, sigma=0.5, jacobian=1, drop=(), **replace) -> dict[str, np.ndarray]:
    """A material whose VNDF is constant and RGB table is ``colour``: f·cos θ_o = colour · ndf / (4 sigma).

    Fields given by keyword replace the material's; fields named in ``drop`` are left out.
    """
    theta_i = np.linspace(0, np.pi / 2, 4, dtype=np.float32)
    fields = {
        "description": np.frombuffer(b"flat test material", np.uint8),
        "phi_i": np.zeros(1, np.float32),
        "theta_i": theta_i,
        "sigma": np.full((2, 16), sigma, np.float32),
        "ndf": np.full((2, 16), ndf, np.float32),
        "vndf": np.ones((1, 4, 8, 8), np.float32),
        "rgb": np.broadcast_to(np.float32(colour)[None, None, :, None, None], (1, 4, 3, 6, 6)).copy(),
        "jacobian": np.array([jacobian], np.uint8),
    }
    fields.update(replace)
    return {name: a for name, a in fields.items() if name not in drop}


def write(tmp_path: Path, data: bytes, name: str = "material.bsdf") -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def upper_hemisphere(rng: np.random.Generator, n: int, z_min: float = 0.02) -> np.ndarray:
    z = rng.uniform(z_min, 1.0, n)
    phi = rng.uniform(0.0, 2 * np.pi, n)
    rho = np.sqrt(1.0 - z * z)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)


def direction_pairs(seed: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Random pairs, a quarter of them near the mirror direction (the highlights), a few
    below the horizon; rounded to float32 so that Mitsuba sees exactly the same directions."""
    rng = np.random.default_rng(seed)
    wi, wo = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    near = rng.random(n) < 0.25
    mirror = wi * np.array([-1.0, -1.0, 1.0]) + rng.normal(0.0, 0.04, (n, 3))
    mirror[:, 2] = np.abs(mirror[:, 2]) + 0.02
    wo[near] = mirror[near] / np.linalg.norm(mirror[near], axis=1, keepdims=True)
    below = rng.random(n) < 0.03
    wo[below, 2] *= -1
    return wi.astype(np.float32).astype(np.float64), wo.astype(np.float32).astype(np.float64)


# Mitsuba runs in a child process: selecting its scalar_rgb variant here would stay selected
# for the rest of the session, and the plugin tests need llvm_ad_rgb.
MITSUBA_SCRIPT = textwrap.dedent("""
    import json, sys, time
    import numpy as np
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    jobs = json.loads(sys.argv[1])
    ctx, si = mi.BSDFContext(), mi.SurfaceInteraction3f()
    for job in jobs:
        bsdf = mi.load_dict({"type": "measured", "filename": job["bsdf"]})
        pairs = np.load(job["pairs"])
        wi, wo = pairs["wi"].tolist(), pairs["wo"].tolist()
        out = np.empty((len(wi), 3))
        start = time.perf_counter()
        for k in range(len(wi)):
            si.wi = mi.Vector3f(wi[k])
            out[k] = bsdf.eval(ctx, si, mi.Vector3f(wo[k]))
        np.save(job["out"], out)
        print(json.dumps({"bsdf": job["bsdf"], "seconds": time.perf_counter() - start}))
""")


@pytest.fixture(scope="module")
def mitsuba_reference(tmp_path_factory):
    """Mitsuba's f·cos θ_o at ``direction_pairs(i, N_PAIRS)`` for each RGL file i, and its timings."""
    if not HAVE_MITSUBA:
        pytest.skip("mitsuba is not installed (pip install -e '.[test]')")
    paths = [RGL_DIR / f"{name}.bsdf" for name in RGL_NAMES]
    if not any(p.is_file() for p in paths):
        pytest.skip(f"no RGL measured materials in {RGL_DIR} (set FRENBRDF_SHARED_DATA)")
    folder = tmp_path_factory.mktemp("mitsuba-measured")
    jobs = []
    for i, path in enumerate(paths):
        if path.is_file():
            wi, wo = direction_pairs(i, N_PAIRS)
            np.savez(folder / f"{i}.npz", wi=wi, wo=wo)
            jobs.append({"bsdf": str(path), "pairs": str(folder / f"{i}.npz"), "out": str(folder / f"{i}.npy")})
    run = subprocess.run([sys.executable, "-c", MITSUBA_SCRIPT, json.dumps(jobs)], capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, f"Mitsuba failed:\n{run.stderr[-3000:]}"
    timings = {Path(t["bsdf"]).stem: t["seconds"] for t in map(json.loads, run.stdout.split("\n")[:-1])}
    return {Path(job["bsdf"]).stem: np.load(job["out"]) for job in jobs}, timings


@pytest.mark.parametrize("index,name", list(enumerate(RGL_NAMES)))
def test_agrees_with_mitsuba_measured(index, name, mitsuba_reference):
    path = rgl_file(name)
    references, timings = mitsuba_reference
    wi, wo = direction_pairs(index, N_PAIRS)
    measurement = BsdfMeasurement.read(path)
    ours, fast = measurement.eval(wi, wo, double=True), measurement.eval(wi, wo)

    # Mitsuba returns f·cos θ_o without clamping negative (out-of-gamut) values.
    with np.errstate(divide="ignore", invalid="ignore"):
        reference = np.where(wo[:, 2:] > 0, references[name] / wo[:, 2:], 0.0)
    reference = np.maximum(reference, 0.0)
    assert np.all(ours[wo[:, 2] <= 0] == 0) and np.all(ours >= 0) and np.all(np.isfinite(ours))
    # Mitsuba computes in float32: its own result moves by ~1e-5 (relative) when an input
    # moves by one float32 ulp, so that is the scale of the agreement.
    scale = reference.max()
    error = np.abs(ours - reference)
    relative = error[reference > 1e-2 * scale] / reference[reference > 1e-2 * scale]
    print(f"{name}: {N_PAIRS} pairs, max abs error {error.max():.2e} (max value {scale:.3g}), "
          f"max rel error {relative.max():.2e} (values > 1% of max), median {np.median(relative):.1e}; "
          f"Mitsuba {timings[name]:.2f} s")
    np.testing.assert_allclose(ours, reference, rtol=2e-4, atol=2e-6 * scale)
    assert np.median(relative) < 2e-6
    # The float32 default agrees with Mitsuba as well, and with float64 to ~1e-5 (rust/bsdf/batch_tests.rs).
    np.testing.assert_allclose(fast, reference, rtol=2e-4, atol=2e-6 * scale)
    np.testing.assert_allclose(fast, ours, rtol=1e-4, atol=1e-6 * scale)


def test_real_file_properties():
    measurement = BsdfMeasurement.read(rgl_file("paper_white_rgb"))
    assert measurement.description == "White A4 paper (160 gsm)"
    assert measurement.isotropic and measurement.jacobian and measurement.reduction == 1
    assert measurement.fields["rgb"] == ("float32", (1, 8, 3, 32, 32))
    assert measurement.fields["jacobian"] == ("uint8", (1,))
    assert measurement.theta_i.shape == (8,) and measurement.theta_i[-1] == pytest.approx(np.pi / 2)
    assert Path(measurement.path).name == "paper_white_rgb.bsdf"
    assert "White A4 paper" in repr(measurement)


def test_flat_material_is_exact(tmp_path):
    path = write(tmp_path, tensor_file(flat_material()))
    measurement = BsdfMeasurement.read(path)
    rng = np.random.default_rng(5)
    wi, wo = upper_hemisphere(rng, 1000, 1e-3), upper_hemisphere(rng, 1000, 1e-3)
    f = measurement.eval(wi, wo, double=True)
    # f·cos θ_o = rgb · D / (4σ) = rgb; inputs need not be unit vectors.
    np.testing.assert_allclose(f * wo[:, 2:], np.broadcast_to(np.float32([0.2, 0.5, 0.7]), f.shape), rtol=1e-7)
    np.testing.assert_allclose(measurement.eval(3 * wi, 0.5 * wo, double=True), f, rtol=1e-12)
    # The float32 default, to float32's precision.
    np.testing.assert_allclose(measurement.eval(3 * wi, 0.5 * wo), f, rtol=1e-6)
    wo[:, 2] *= -1
    assert np.all(measurement.eval(wi, wo) == 0) and np.all(measurement.eval(wi, wo, double=True) == 0)
    # Without the Jacobian flag the table is used as it is; negative values clamp to 0.
    path = write(tmp_path, tensor_file(flat_material(colour=(0.3, -0.1, 0.0), sigma=1e-3, jacobian=0)), "b.bsdf")
    for double in (True, False):
        f = BsdfMeasurement.read(path).eval(np.array([[0.0, 0.0, 1.0]]), np.array([[0.6, 0.0, 0.8]]), double)
        np.testing.assert_allclose(f, [[0.3 / 0.8, 0.0, 0.0]], rtol=1e-7 if double else 1e-6)


def test_eval_checks_its_arguments(tmp_path):
    measurement = BsdfMeasurement.read(write(tmp_path, tensor_file(flat_material())))
    good = np.tile([0.0, 0.0, 1.0], (4, 1))
    with pytest.raises(ValueError, match=r"wi must have shape \(n, 3\)"):
        measurement.eval(good[:, :2].copy(), good)
    with pytest.raises(ValueError, match="wo must be C-contiguous"):
        measurement.eval(good, np.asfortranarray(good))
    with pytest.raises(ValueError, match="wi has 4 rows but wo has 3"):
        measurement.eval(good, good[:3])
    bad = good.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match="wo row 2 is not a finite non-zero vector"):
        measurement.eval(good, bad)
    assert measurement.eval(good[:0], good[:0]).shape == (0, 3)


def test_missing_file(tmp_path):
    path = tmp_path / "nowhere.bsdf"
    with pytest.raises(FileNotFoundError) as caught:
        BsdfMeasurement.read(path)
    assert caught.value.filename == str(path) and str(path) in str(caught.value)
    with pytest.raises(IsADirectoryError):
        BsdfMeasurement.read(tmp_path)


def bad_files() -> dict[str, tuple[bytes, str]]:
    good = tensor_file(flat_material())
    header_end = good.index(b"jacobian") + len(b"jacobian") + 2 + 1 + 8 + 8
    return {
        "wrong magic": (b"tensor_fila\0" + good[12:], "not a tensor file"),
        "MERL file": (struct.pack("<3i", 90, 90, 180) + bytes(64), "not a tensor file"),
        "empty": (b"", r"truncated: the magic number needs 12 bytes at byte offset 0, but the file is 0 bytes"),
        "version 2.0": (tensor_file(flat_material(), version=b"\x02\x00"), r"version 2\.0 is not supported"),
        "cut in the header": (good[:40], r"truncated: .* field 1 \(of 8\)|truncated: the .* of field"),
        "cut after the header": (good[:header_end + 3], r"field `[a-z_]+` \(.*\) claims .* but the file is"),
        "cut in the data": (good[:-8], r"field `jacobian` .* but the file is"),
        "rgb as float64": (tensor_file(flat_material(rgb=np.ones((1, 4, 3, 6, 6)))),
                           r"field `rgb` is float64 with shape \[1, 4, 3, 6, 6\]; expected float32"),
        "rgb with 4 channels": (tensor_file(flat_material(rgb=np.ones((1, 4, 4, 6, 6), np.float32))),
                                r"field `rgb` has shape \[1, 4, 4, 6, 6\]; expected \(phi_i, theta_i, 3, ny, nx\)"),
        "vndf of rank 3": (tensor_file(flat_material(vndf=np.ones((4, 8, 8), np.float32))),
                           r"field `vndf` is float32 with shape \[4, 8, 8\]; expected float32 with 4 dimensions"),
        "no rgb": (tensor_file(flat_material(drop=("rgb",))), "has no field `rgb`"),
        "spectral": (tensor_file(flat_material(drop=("rgb",)) | {
            "wavelengths": np.linspace(360, 1000, 5, dtype=np.float32),
            "spectra": np.ones((1, 4, 5, 6, 6), np.float32)}), "spectral BSDF file .* not supported"),
        "zero sigma": (tensor_file(flat_material(sigma=0.0)), "field `sigma` value 0 is 0"),
        "incidence below the surface": (
            tensor_file(flat_material(theta_i=np.linspace(0, 2.0, 4, dtype=np.float32))),
            r"field `theta_i` value 3 is 2 rad; an incidence angle lies in 0 … π/2"),
        "NaN incidence": (tensor_file(flat_material(theta_i=np.float32([0, 0.5, np.nan, 1.5]))),
                          "field `theta_i` value 2 is NaN rad"),
        "jacobian flag 7": (tensor_file(flat_material(jacobian=7)), "field `jacobian` is 7; the flag is 0 or 1"),
        "NaN in the VNDF": (tensor_file(flat_material(vndf=np.full((1, 4, 8, 8), np.nan, np.float32))),
                            "field `vndf`: value 0 is NaN"),
    }


@pytest.mark.parametrize("case", list(bad_files()))
def test_bad_files_raise_bsdf_format_error(tmp_path, case):
    data, message = bad_files()[case]
    path = write(tmp_path, data)
    with pytest.raises(BsdfFormatError, match=message) as caught:
        BsdfMeasurement.read(path)
    assert str(caught.value).startswith(f"{path}: ")
    assert isinstance(caught.value, ValueError)


def test_absurd_sizes_do_not_allocate(tmp_path):
    """A shape claiming 2^60 elements, or a field count of 2^32 − 1, fails at once."""
    good = tensor_file(flat_material())
    at = good.index(b"vndf") + 4 + 2 + 1 + 8  # the vndf's shape
    huge = good[:at] + struct.pack("<4Q", 1 << 60, 1, 1, 1) + good[at + 32:]
    with pytest.raises(BsdfFormatError, match=r"field `vndf` .* claims 1152921504606846976 elements \(4611686018427387904 bytes\)"):
        BsdfMeasurement.read(write(tmp_path, huge))
    many = good[:14] + struct.pack("<I", 2**32 - 1) + good[18:]
    with pytest.raises(BsdfFormatError, match=r"declares 4294967295 fields; a tensor file frenbrdf reads has at most 4096"):
        BsdfMeasurement.read(write(tmp_path, many, "many.bsdf"))


def test_written_file_round_trips_through_the_reader(tmp_path):
    fields = flat_material()
    fields["extra"] = np.arange(6, dtype="<i8").reshape(2, 3)
    measurement = BsdfMeasurement.read(write(tmp_path, tensor_file(fields)))
    assert measurement.fields == {name: (a.dtype.name, a.shape) for name, a in fields.items()}
    assert measurement.description == "flat test material"
    np.testing.assert_array_equal(measurement.theta_i, fields["theta_i"])
