"""The one table of a material's file formats (frenbrdf.io.formats): every suffix reaches its reader and writer,
whatever its case; any other suffix is refused with one message; what is written reads back the same."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
import torch

import frenbrdf
from frenbrdf.io import FORMATS, read_material, read_samples, read_table, write_material, write_samples
from frenbrdf.io.bsdf import MeasuredBSDF
from frenbrdf.io.formats import read_measured
from frenbrdf.io.nbrdf import NBRDFWeights
from frenbrdf.io.samples import MIN_SAMPLES, Measurements
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.models.nbrdf import NBRDF, as_brdf

from ..conftest import constant_table, random_layers, random_nbrdf_params, write_keras_h5
from .test_bsdf_native import flat_material, tensor_file

MATERIALS = (".binary", ".bsdf", ".pt", ".h5")
SAMPLES = (".csv", ".npz", ".astm")


def _unit(rng, n):
    theta, phi = rng.uniform(0.1, 1.4, n), rng.uniform(0, 2 * np.pi, n)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def _measurements(n: int = MIN_SAMPLES + 10, seed: int = 0) -> Measurements:
    rng = np.random.default_rng(seed)
    return Measurements(rng.uniform(0.01, 2.0, (n, 3)), _unit(rng, n), _unit(rng, n))


def _nbrdf(ordered: bool = False) -> NBRDF:
    return NBRDF(random_nbrdf_params(), LogRelativeMapping(np.array([0.1, 0.2, 0.3]), 0.01, 1.0), ordered)


def _write(folder, suffix: str, stem: str = "m"):
    """A small valid file of each format."""
    path = folder / f"{stem}{suffix}"
    if suffix.lower() == ".binary":
        frenbrdf.write_merl(path, constant_table(0.2))
    elif suffix.lower() == ".bsdf":
        path.write_bytes(tensor_file(flat_material()))
    elif suffix.lower() == ".pt":
        write_material(path, _nbrdf().weights())
    elif suffix.lower() == ".h5":
        write_keras_h5(path, random_layers([6, 8, 3], seed=4))
    else:
        write_samples(path, _measurements())
    return path


def test_the_table_holds_every_format_once():
    assert set(FORMATS) == {*MATERIALS, *SAMPLES}
    assert all(suffix == suffix.lower() and entry.suffix == suffix for suffix, entry in FORMATS.items())
    assert {s for s, e in FORMATS.items() if e.write} == {".binary", ".pt", ".csv", ".npz", ".astm"}
    assert frenbrdf.read_material is read_material and frenbrdf.read_samples is read_samples


@pytest.mark.parametrize("suffix", sorted(FORMATS))
def test_every_suffix_reaches_its_reader_whatever_its_case(tmp_path, monkeypatch, suffix):
    seen = []
    monkeypatch.setitem(FORMATS, suffix, dataclasses.replace(FORMATS[suffix], read=lambda p: seen.append(p) or "read"))
    reader = read_samples if suffix in SAMPLES else read_material
    for name in (suffix, suffix.upper()):
        path = tmp_path / f"file{name}"
        path.write_bytes(b"x")
        assert reader(path) == "read" and seen[-1] == path
    assert len(seen) == 2


def test_each_format_reads_as_what_it_holds(tmp_path):
    table = read_material(_write(tmp_path, ".binary"))
    np.testing.assert_array_equal(table, frenbrdf.read_merl(tmp_path / "m.binary"))
    assert isinstance(read_material(_write(tmp_path, ".bsdf")), MeasuredBSDF)
    assert isinstance(read_measured(tmp_path / "m.bsdf"), MeasuredBSDF)
    np.testing.assert_array_equal(read_measured(tmp_path / "m.binary"), table)
    for suffix, what in ((".pt", "saved NBRDF"), (".h5", "Keras NBRDF")):
        weights = read_material(_write(tmp_path, suffix))
        assert isinstance(weights, NBRDFWeights) and weights.what == what
        assert weights.source == str(tmp_path / f"m{suffix}")
        assert isinstance(as_brdf(weights), NBRDF) and len(as_brdf(weights)) == 1
    assert as_brdf(table) is table
    for suffix in SAMPLES:
        samples = read_samples(_write(tmp_path, suffix))
        assert samples.kind == suffix[1:] and len(samples) == MIN_SAMPLES + 10 and samples.truth is None
    for suffix, kind in ((".binary", "merl"), (".bsdf", "bsdf")):
        drawn = read_samples(tmp_path / f"m{suffix}", samples=300, seed=2)
        assert drawn.kind == kind and len(drawn) == 300 and drawn.table.shape == (3, 90, 90, 180)
        assert drawn.truth is not None and drawn.source == str(tmp_path / f"m{suffix}")
        np.testing.assert_array_equal(drawn.values, read_samples(tmp_path / f"m{suffix}", samples=300, seed=2).values)


def test_upper_case_suffixes_read_as_lower_case_ones(tmp_path):
    for suffix in MATERIALS:
        loud, quiet = _write(tmp_path, suffix.upper(), "loud"), _write(tmp_path, suffix, "quiet")
        assert type(read_material(loud)) is type(read_material(quiet))
    for suffix in SAMPLES:
        loud = _write(tmp_path, suffix.upper(), "loud")
        np.testing.assert_array_equal(read_samples(loud).values, read_samples(_write(tmp_path, suffix, "q")).values)
    assert read_table(_write(tmp_path, ".BSDF", "loud")).shape == (3, 90, 90, 180)


def test_another_suffix_is_refused_naming_the_file_and_the_suffixes_read(tmp_path):
    for name in ("notes.txt", "fit.weights", "material"):
        (tmp_path / name).write_bytes(b"\0" * 64)
    cases = [
        (read_material, "notes.txt", r"read_material reads \.binary \(a MERL table\), \.bsdf \(an RGL measurement\), "
                                     r"\.pt \(a saved NBRDF\), \.h5 \(a published Keras NBRDF\); this file has the "
                                     r"suffix '\.txt'"),
        (read_material, "fit.weights", r"read_material reads .*; this file has the suffix '\.weights'"),
        (read_material, "material", r"read_material reads .*; this file has no suffix$"),
        (read_samples, "notes.txt", r"read_samples reads \.binary \(a MERL table\), \.bsdf \(an RGL measurement\), "
                                    r"\.csv \(samples in CSV\), \.npz \(samples in NPZ\), \.astm \(ASTM E1392 scatter "
                                    r"data\); this file has the suffix"),
        (read_table, "notes.txt", r"read_table reads \.binary \(a MERL table\), \.bsdf \(an RGL measurement\); "),
    ]
    for reader, name, message in cases:
        with pytest.raises(ValueError, match=rf"^{re.escape(str(tmp_path / name))}: {message}"):
            reader(tmp_path / name)
    # A format that holds something else: named as what it is.
    with pytest.raises(ValueError, match=r"s\.csv: read_material reads .*; this file is samples in CSV \(\.csv\)"):
        read_material(_write(tmp_path, ".csv", "s"))
    with pytest.raises(ValueError, match=r"m\.pt: read_samples reads .*; this file is a saved NBRDF \(\.pt\)"):
        read_samples(_write(tmp_path, ".pt"))
    with pytest.raises(ValueError, match=r"m\.h5: read_table reads .*; this file is a published Keras NBRDF"):
        read_table(_write(tmp_path, ".h5"))
    with pytest.raises(ValueError, match=r"m\.pt: read_measured reads \.binary .*, \.bsdf .*; this file is a saved"):
        read_measured(tmp_path / "m.pt")
    # The file is checked first: what is not there, or not a file, is named as such.
    with pytest.raises(FileNotFoundError, match="absent.txt"):
        read_material(tmp_path / "absent.txt")
    with pytest.raises(IsADirectoryError, match="got a folder"):
        read_samples(tmp_path)


def test_writers_refuse_what_frenbrdf_does_not_write(tmp_path):
    with pytest.raises(ValueError, match=r"m\.bsdf: write_material writes \.binary \(a MERL table\), \.pt \(a saved "
                                         r"NBRDF\); this file is an RGL measurement"):
        write_material(tmp_path / "m.bsdf", constant_table(0.2))
    with pytest.raises(ValueError, match=r"m\.h5: write_material writes .*; this file is a published Keras NBRDF"):
        write_material(tmp_path / "m.h5", _nbrdf().weights())
    with pytest.raises(ValueError, match=r"m\.binary: write_samples writes \.csv \(samples in CSV\), \.npz \(samples "
                                         r"in NPZ\), \.astm \(ASTM E1392 scatter data\); this file is a MERL table"):
        write_samples(tmp_path / "m.binary", _measurements())
    with pytest.raises(TypeError, match=r"m\.pt: a saved NBRDF holds NBRDFWeights"):
        write_material(tmp_path / "m.pt", _nbrdf())
    with pytest.raises(TypeError, match=r"m\.csv: a file of samples holds Measurements"):
        write_samples(tmp_path / "m.csv", np.zeros((60, 9)))
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_table_round_trips_exactly(tmp_path):
    table = constant_table(0.3)
    table[1, 10, 20, 30] = 0.123456789
    for name in ("t.binary", "T.BINARY"):
        write_material(tmp_path / name, table)
        np.testing.assert_array_equal(read_material(tmp_path / name), table)


@pytest.mark.parametrize("ordered", [False, True])
def test_an_nbrdf_round_trips_exactly(tmp_path, ordered):
    nbrdf = _nbrdf(ordered)
    write_material(tmp_path / "n.pt", nbrdf.weights())
    again = NBRDF.from_weights(read_material(tmp_path / "n.pt"))
    assert again.ordered == ordered and len(again) == 1
    assert all(torch.equal(a, b) for a, b in zip(again.params, nbrdf.params, strict=True))
    np.testing.assert_array_equal(again.mapping.reference, np.float32(nbrdf.mapping.reference))  # stored as float32
    assert (again.mapping.epsilon, again.mapping.offset) == (nbrdf.mapping.epsilon, nbrdf.mapping.offset)
    wi, wo = _unit(np.random.default_rng(1), 20), _unit(np.random.default_rng(2), 20)
    np.testing.assert_allclose(again(wi, wo), nbrdf(wi, wo), rtol=1e-6)


@pytest.mark.parametrize("suffix", SAMPLES)
def test_samples_round_trip_exactly(tmp_path, suffix):
    written = _measurements(seed=3)
    path = tmp_path / f"s{suffix}"
    write_samples(path, written)
    read = read_samples(path)
    assert read.kind == suffix[1:] and read.source == str(path)
    np.testing.assert_array_equal(read.values, written.values)  # written exactly
    for name in ("wi", "wo"):  # normalised as they are read: to the last bit or two (an .astm holds angles)
        tolerance = {"rtol": 0, "atol": 1e-15} if suffix == ".astm" else {"rtol": 1e-15, "atol": 0}
        np.testing.assert_allclose(getattr(read, name), getattr(written, name), **tolerance)


def test_samples_drawn_from_a_measurement_convert_and_read_back(tmp_path):
    source = _write(tmp_path, ".bsdf")
    drawn = read_samples(source, samples=200, seed=5)
    write_samples(tmp_path / "drawn.csv", drawn)
    again = read_samples(tmp_path / "drawn.csv")
    np.testing.assert_allclose(again.values, drawn.values, rtol=1e-15)
    np.testing.assert_allclose(again.values, drawn.truth(again.wi, again.wo), rtol=1e-12)


def test_weights_that_are_no_network_are_named_by_their_file(tmp_path):
    path = tmp_path / "wide.pt"
    weights = _nbrdf().weights()
    write_material(path, dataclasses.replace(weights, params=[torch.zeros(8, 5), *weights.params[1:]]))
    loaded = read_material(path)  # the file itself is whole
    with pytest.raises(ValueError, match=r"wide\.pt: not a valid saved NBRDF: NBRDF: layer 1"):
        as_brdf(loaded)
