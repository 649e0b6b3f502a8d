"""Issue 45: a file a user names is checked before its costs are paid, and its values by one rule.

- A ``.bsdf`` of any size (a sparse 20 GB file, random bytes, a header declaring gigabytes) is
  refused from its header, without reading or allocating what it declares.
- An ``.npz`` member's own ``.npy`` header is checked (shape × item size, pickles) before numpy
  allocates anything.
- An HDF5 weight file's links are walked first: external links and data, and soft links that do
  not resolve, are named errors.
- A material's values pass one check, whatever reads them: training, reconstruction, rendering
  and conversion refuse the same files with the same message.
"""

from __future__ import annotations

import io
import os
import struct
import time
import zipfile

import h5py
import numpy as np
import pytest

import frenbrdf
from frenbrdf import cli
from frenbrdf.data.folders import read_tables
from frenbrdf.exceptions import BsdfFormatError, MerlFormatError
from frenbrdf.io import read_material, read_samples, read_table
from frenbrdf.io.keras import read_keras_nbrdf
from frenbrdf.io.paths import checked_npz
from frenbrdf.io.reflectance import MAX_REFLECTANCE, check_reflectance

from ..conftest import constant_table, random_layers, write_keras_h5
from .test_bsdf_native import flat_material, tensor_file

#: The size of the sparse files: far more than the machine could allocate.
HUGE = 20 << 30
#: The cap on what a tensor file may declare (rust/bsdf/tensor_file.rs: MAX_BYTES).
MAX_BSDF_BYTES = 256 << 20


def sparse(path, head: bytes = b"", size: int = HUGE):
    """``path`` holding ``head``, then zeros up to ``size`` bytes that take no disk space."""
    path.write_bytes(head)
    os.truncate(path, size)
    return path


def huge_bsdfs(folder) -> dict[str, tuple[object, str]]:
    """Files named .bsdf that no reader may load whole, with what their error must say."""
    good = tensor_file(flat_material())
    at = good.index(b"rgb") + 3 + 2 + 1 + 8  # the rgb's shape
    declares = good[:at] + struct.pack("<5Q", 1, 4, 3, 1 << 12, 1 << 12) + good[at + 40:]  # 805 MB of float32
    return {
        "zeros": (sparse(folder / "zeros.bsdf"), "not a tensor file"),
        "random": (sparse(folder / "random.bsdf", np.random.default_rng(0).bytes(1 << 16)), "not a tensor file"),
        "declares": (sparse(folder / "declares.bsdf", declares),
                     rf"field `rgb` \(float32 \[1, 4, 3, 4096, 4096\].*past the {MAX_BSDF_BYTES} bytes"),
    }


def test_a_huge_file_named_bsdf_is_refused_from_its_header(tmp_path):
    for name, (path, message) in huge_bsdfs(tmp_path).items():
        start = time.perf_counter()
        with pytest.raises(BsdfFormatError, match=message) as caught:
            frenbrdf.read_bsdf(path)
        assert str(caught.value).startswith(f"{path}: "), name
        assert time.perf_counter() - start < 2, f"{name}: read more than its header"
    # Trailing bytes past what the fields declare are never read: a valid file padded to 20 GB reads.
    padded = sparse(tmp_path / "padded.bsdf", tensor_file(flat_material()))
    assert frenbrdf.read_bsdf(padded).description == "flat test material"


@pytest.mark.parametrize("command", [
    ["reconstruct", "{bsdf}", "--out", "{tmp}/o", "--refine", "none", "--quiet"],
    ["render", "{bsdf}", "--out", "{tmp}/x.png", "--resolution", "16"],
    ["convert", "{bsdf}", "{tmp}/x.binary"],
])
def test_the_cli_refuses_a_huge_bsdf_with_exit_2(tmp_path, capsys, command):
    for path, _ in huge_bsdfs(tmp_path).values():
        with pytest.raises(SystemExit) as stop:
            cli.main([part.format(bsdf=path, tmp=tmp_path) for part in command])
        err = capsys.readouterr().err
        assert stop.value.code == 2 and str(path) in err
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err


# ---------------------------------------------------------------------------------------
# .npz members whose .npy header is not what the zip says

def npz(path, members: dict[str, bytes]):
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


def npy(shape, dtype="<f8", data: bytes = b"") -> bytes:
    """An .npy header declaring ``shape`` and ``dtype``, followed by ``data``."""
    out = io.BytesIO()
    np.lib.format.write_array_header_1_0(out, {"descr": dtype, "fortran_order": False, "shape": shape})
    return out.getvalue() + data


def test_an_npy_header_declaring_more_than_its_member_is_refused(tmp_path):
    huge = npz(tmp_path / "huge.npz", {"r.npy": npy((10**11,), data=bytes(80))})
    with pytest.raises(ValueError, match=r"huge.npz: r.npy declares an array of shape \(100000000000,\) "
                                         r"\(float64, 800,000,000,000 bytes\), more than"):
        read_samples(huge)
    short = npz(tmp_path / "short.npz", {"r.npy": npy((1000,), data=bytes(80))})
    with pytest.raises(ValueError, match=r"short.npz: r.npy declares .* 8,000 bytes\), but holds only 80 bytes"):
        checked_npz(short)
    # Elements of no size still count: 10¹¹ of them would be allocated as soon as they are converted.
    empty = npz(tmp_path / "empty.npz", {"r.npy": npy((10**11,), dtype="|V0")})
    with pytest.raises(ValueError, match="empty.npz: r.npy declares an array of shape"):
        checked_npz(empty)
    good = npz(tmp_path / "good.npz", {"r.npy": npy((10,), data=np.arange(10.0).tobytes())})
    np.testing.assert_array_equal(checked_npz(good)["r"], np.arange(10.0))


def test_a_pickled_npz_says_so(tmp_path):
    pickled = tmp_path / "pickled.npz"
    np.savez(pickled, r=np.array([{"a": 1}, None], dtype=object))
    with pytest.raises(ValueError, match="pickled.npz: r.npy holds pickled Python objects, which frenbrdf never "
                                         "loads") as caught:
        read_samples(pickled)
    assert "damaged" not in str(caught.value) and "allow_pickle" not in str(caught.value)


# ---------------------------------------------------------------------------------------
# HDF5 weight files with odd structure

def _soft_loop(file):
    file["a"] = h5py.SoftLink("/a")


def _dangling(file):
    file["dense_1/dense_1/extra"] = h5py.SoftLink("/nowhere")


def _external_link(file):
    file["elsewhere"] = h5py.ExternalLink("other.h5", "/dense_1")


def _external_data(file):
    file.create_dataset("raw", shape=(4,), dtype="<f8", external=[("raw.bin", 0, 32)])


def _two_loops(file):
    file["x"], file["y"] = h5py.SoftLink("/y"), h5py.SoftLink("/x")


@pytest.mark.parametrize("edit, message", [
    (_soft_loop, r"/a is a loop of soft links to /a, which does not resolve"),
    (_two_loops, r"/x is a loop of soft links to /y"),
    (_dangling, r"/dense_1/dense_1/extra is a link to nothing to /nowhere"),
    (_external_link, r"/elsewhere is an external link to other.h5:/dense_1; frenbrdf reads nothing outside"),
    (_external_data, r"dataset /raw keeps its data in other files"),
])
def test_odd_hdf5_structure_is_a_named_error(tmp_path, edit, message):
    path = write_keras_h5(tmp_path / "weights.h5", random_layers([6, 4, 3]))
    with h5py.File(path, "a") as file:
        edit(file)
    for reader in (read_keras_nbrdf, read_material):
        with pytest.raises(ValueError, match=message) as caught:
            reader(path)
        assert str(caught.value).startswith(f"{path}: ")


def test_a_soft_link_that_resolves_and_a_hard_link_cycle_are_fine(tmp_path):
    layers = random_layers([6, 4, 3])
    path = write_keras_h5(tmp_path / "weights.h5", layers)
    with h5py.File(path, "a") as file:
        file["alias"] = h5py.SoftLink("/dense_1/dense_1/bias:0")
        file["dense_1/dense_1/root"] = file["/"]  # a hard link back to the root
    loaded = read_keras_nbrdf(path)
    np.testing.assert_allclose(loaded[0][0], np.float32(layers[0][0]))


# ---------------------------------------------------------------------------------------
# One rule for a material's values

def test_check_reflectance_counts_and_locates_bad_values():
    values = np.zeros((3, 4))
    values[1, 2] = -1  # missing markers pass
    check_reflectance(values, "m.binary")
    values[2, 1], values[2, 3] = np.inf, np.nan
    with pytest.raises(ValueError, match=r"^m.binary: 2 of its values are NaN or infinite \(the first at index "
                                         r"\(a, b\) \(2, 1\)\)$"):
        check_reflectance(values, "m.binary", axes="(a, b)")
    values[2] = [0, 1e30, 0, 1e9]
    with pytest.raises(MerlFormatError, match=r"2 of its values are above 1e\+08 1/sr \(the largest is 1e\+30, the "
                                              r"first at index \(2, 1\)\)"):
        check_reflectance(values, "m.binary", error=MerlFormatError)
    check_reflectance(np.full(3, MAX_REFLECTANCE), "m.binary")


def _merl_with_spikes(path):
    table = constant_table(0.1)
    table[1, 10, 20, 30] = 1e44
    table[2, 11, 20, 30] = 1e12
    frenbrdf.write_merl(path, table)
    return path


def test_a_material_with_absurd_values_is_refused_by_every_reader(tmp_path):
    merl = _merl_with_spikes(tmp_path / "spikes.binary")
    bsdf = tmp_path / "spikes.bsdf"
    bsdf.write_bytes(tensor_file(flat_material(colour=(0.2, 1e30, 0.5))))
    # Finite stored values, but 10¹¹/sr once the Jacobian D / (4σ) is applied: caught at the MERL bins.
    steep = tmp_path / "steep.bsdf"
    steep.write_bytes(tensor_file(flat_material(sigma=1e-12)))
    expected = {
        merl: r"spikes.binary: 2 of its values are above 1e\+08 1/sr \(the largest is 1e\+44, the first at index "
              r"\(channel, θ_h, θ_d, φ_d\) \(1, 10, 20, 30\)\)",
        bsdf: r"spikes.bsdf: 144 of its values of field rgb are above 1e\+08 1/sr .* \(0, 0, 1, 0, 0\)\)",
        steep: r"steep.bsdf: [\d,]+ of its values at the MERL bins are above 1e\+08 1/sr",
    }
    readers = {
        "training": lambda path: read_tables([path], progress=False),
        "reconstruction": lambda path: read_samples(path, samples=100),
        "conversion": read_table,
        "rendering": read_material,
    }
    for path, message in expected.items():
        for use, reader in readers.items():
            if path == steep and use == "rendering":
                continue  # rendered as measured: its table is never made
            with pytest.raises(ValueError, match=message):
                reader(path)
    # Raw stored values are checked in physical units too.
    with pytest.raises(MerlFormatError, match="spikes.binary: 2 of its values"):
        frenbrdf.read_merl(merl, physical_units=False)
