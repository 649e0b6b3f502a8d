"""MERL file reading and writing: exact round trips and clean errors on bad input."""

from __future__ import annotations

import os
import struct

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import frenbrdf
from frenbrdf import MerlFormatError
from frenbrdf.io.merl import CHANNEL_SCALES, FILE_BYTES, SHAPE

HEADER = struct.pack("<3i", 90, 90, 180)


def raw_file(stored: np.ndarray) -> bytes:
    """A MERL file's bytes from stored (unscaled) values, written by numpy as reference."""
    return HEADER + stored.astype("<f8").tobytes()


def test_read_matches_a_direct_numpy_decoding(tmp_path):
    rng = np.random.default_rng(0)
    stored = rng.uniform(-1, 5000, size=SHAPE)
    path = tmp_path / "a.binary"
    path.write_bytes(raw_file(stored))

    table = frenbrdf.read_merl(path)
    assert table.dtype == np.float64 and table.shape == SHAPE
    expected = stored * np.array(CHANNEL_SCALES)[:, None, None, None]
    np.testing.assert_array_equal(table, expected)
    np.testing.assert_array_equal(frenbrdf.read_merl(path, physical_units=False), stored)


def test_missing_measurements_are_kept_exactly(tmp_path):
    stored = np.full(SHAPE, 100.0)
    stored[1, 5, 89, 7] = -1.0
    stored[2, 0, 0, 0] = -0.5
    path = tmp_path / "a.binary"
    path.write_bytes(raw_file(stored))
    table = frenbrdf.read_merl(path)
    assert table[1, 5, 89, 7] == -1.0 * CHANNEL_SCALES[1]
    assert table[2, 0, 0, 0] == -0.5 * CHANNEL_SCALES[2]
    mask = frenbrdf.valid_mask(table)
    assert mask.shape == (90, 90, 180) and mask.sum() == 90 * 90 * 180 - 2


def test_write_then_read_returns_the_same_table(tmp_path, merl_table):
    path = tmp_path / "a.binary"
    frenbrdf.write_merl(path, merl_table)
    assert path.stat().st_size == FILE_BYTES == 34_992_012
    np.testing.assert_array_equal(frenbrdf.read_merl(path), merl_table)


def test_read_write_reproduces_the_bytes_of_a_written_file(tmp_path, merl_table):
    first, second = tmp_path / "first.binary", tmp_path / "second.binary"
    frenbrdf.write_merl(first, merl_table)
    frenbrdf.write_merl(second, frenbrdf.read_merl(first))
    assert first.read_bytes() == second.read_bytes()


@pytest.mark.parametrize("seed", [0, 1])
def test_any_file_round_trips_exactly(tmp_path, seed):
    """Files from other writers: byte-exact in stored units, value-exact in reflectance."""
    rng = np.random.default_rng(seed)
    stored = rng.lognormal(3.0, 3.0, size=SHAPE) * rng.choice([-1.0, 1.0], size=SHAPE)
    original = tmp_path / "foreign.binary"
    original.write_bytes(raw_file(stored))

    copy = tmp_path / "copy.binary"
    frenbrdf.write_merl(copy, frenbrdf.read_merl(original, physical_units=False), physical_units=False)
    assert copy.read_bytes() == original.read_bytes()

    frenbrdf.write_merl(copy, frenbrdf.read_merl(original))
    np.testing.assert_array_equal(frenbrdf.read_merl(copy), frenbrdf.read_merl(original))


def test_float32_tables_are_written(tmp_path, merl_table):
    path = tmp_path / "a.binary"
    frenbrdf.write_merl(path, merl_table.astype(np.float32))
    np.testing.assert_allclose(frenbrdf.read_merl(path), merl_table.astype(np.float32), rtol=1e-15)


# --- bad input -----------------------------------------------------------------------


def test_wrong_header_dimensions_are_rejected_without_allocating(tmp_path):
    path = tmp_path / "huge.binary"
    path.write_bytes(struct.pack("<3i", 2**31 - 1, 2**31 - 1, 2**31 - 1) + b"\0" * 64)
    with pytest.raises(MerlFormatError, match=r"huge\.binary.*header dimensions are 2147483647"):
        frenbrdf.read_merl(path)
    path.write_bytes(struct.pack("<3i", 90, 90, -180))
    with pytest.raises(MerlFormatError, match="90 × 90 × -180"):
        frenbrdf.read_merl(path)


def test_truncated_file_names_the_sizes(tmp_path, merl_file):
    data = merl_file.read_bytes()
    merl_file.write_bytes(data[:-8])
    with pytest.raises(MerlFormatError, match=r"material\.binary: file is 34992004 bytes .*34992012.*truncated"):
        frenbrdf.read_merl(merl_file)
    merl_file.write_bytes(data + b"\0")
    with pytest.raises(MerlFormatError, match="34992013 bytes"):
        frenbrdf.read_merl(merl_file)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_values_are_located(tmp_path, bad):
    stored = np.ones(SHAPE)
    stored[2, 3, 4, 5] = bad
    path = tmp_path / "nan.binary"
    path.write_bytes(raw_file(stored))
    offset = 12 + 8 * np.ravel_multi_index((2, 3, 4, 5), SHAPE)
    with pytest.raises(MerlFormatError, match=rf"byte offset {offset} \(channel blue, bin \(θ_h 3, θ_d 4, φ_d 5\)\)"):
        frenbrdf.read_merl(path)


def test_missing_path_and_directory_raise_os_errors(tmp_path):
    with pytest.raises(FileNotFoundError) as error:
        frenbrdf.read_merl(tmp_path / "absent.binary")
    assert error.value.filename == str(tmp_path / "absent.binary")
    with pytest.raises(IsADirectoryError):
        frenbrdf.read_merl(tmp_path)
    with pytest.raises(IsADirectoryError):
        frenbrdf.write_merl(tmp_path, np.zeros(SHAPE))
    with pytest.raises(FileNotFoundError):
        frenbrdf.write_merl(tmp_path / "no" / "such" / "folder.binary", np.zeros(SHAPE))


@pytest.mark.parametrize(
    "table, message",
    [
        (np.zeros((3, 90, 90, 179)), r"shape \(3, 90, 90, 179\)"),
        (np.zeros((90, 90, 180)), r"shape \(90, 90, 180\)"),
        (np.zeros(SHAPE, dtype=np.int64), "dtype int64"),
        (np.zeros(SHAPE, dtype=np.complex128), "dtype complex128"),
        (np.full(SHAPE, np.nan), "non-finite value NaN at channel red"),
    ],
)
def test_bad_arrays_are_not_written_and_leave_the_old_file_intact(tmp_path, merl_file, table, message):
    before = merl_file.read_bytes()
    with pytest.raises(MerlFormatError, match=message):
        frenbrdf.write_merl(merl_file, table)
    assert merl_file.read_bytes() == before
    assert os.listdir(tmp_path) == [merl_file.name]  # no temporary file left behind


def test_merl_format_error_is_a_value_error():
    assert issubclass(MerlFormatError, ValueError)


@pytest.fixture(scope="module")
def valid_bytes() -> bytes:
    rng = np.random.default_rng(7)
    return raw_file(rng.uniform(0, 10, size=SHAPE))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=256))
def test_random_bytes_raise_only_clean_errors(tmp_path, data):
    path = tmp_path / "random.binary"
    path.write_bytes(data)
    with pytest.raises(MerlFormatError, match="random.binary"):
        frenbrdf.read_merl(path)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    cut=st.integers(min_value=0, max_value=FILE_BYTES - 1),
    corrupt_at=st.none() | st.integers(min_value=0, max_value=FILE_BYTES - 1),
    corrupt_byte=st.integers(min_value=0, max_value=255),
)
def test_truncated_or_corrupted_files_raise_only_clean_errors(tmp_path, valid_bytes, cut, corrupt_at, corrupt_byte):
    data = bytearray(valid_bytes[:cut])
    if corrupt_at is not None and corrupt_at < cut:
        data[corrupt_at] = corrupt_byte
    path = tmp_path / "cut.binary"
    path.write_bytes(bytes(data))
    with pytest.raises(MerlFormatError, match="cut.binary"):
        frenbrdf.read_merl(path)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(position=st.integers(min_value=12, max_value=FILE_BYTES - 1), byte=st.integers(min_value=0, max_value=255))
def test_a_full_size_file_with_any_one_byte_changed_reads_or_fails_cleanly(tmp_path, valid_bytes, position, byte):
    data = bytearray(valid_bytes)
    data[position] = byte
    path = tmp_path / "flip.binary"
    path.write_bytes(bytes(data))
    try:
        table = frenbrdf.read_merl(path)
    except MerlFormatError as error:  # a flipped exponent bit: a NaN, an infinity or an absurd value, each named
        assert "NaN or infinite" in str(error) or "above 1e+08 1/sr" in str(error)
    else:
        assert np.isfinite(table).all()
