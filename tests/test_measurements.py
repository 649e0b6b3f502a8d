"""Measurement files: CSV and NPZ of samples, MERL files sampled; every bad input named by file and row."""

from __future__ import annotations

import numpy as np
import pytest

import frenbrdf
from frenbrdf.io import read_samples
from frenbrdf.io.samples import FORMS, MIN_SAMPLES

from .conftest import toy_table

VECTORS = FORMS["vectors"]


def samples(n: int = 60, seed: int = 0) -> np.ndarray:
    """``(n, 9)`` valid rows of the vector form: unit directions above the horizon, positive colours."""
    rng = np.random.default_rng(seed)
    theta, phi = rng.uniform(0.1, 1.4, (2, n)), rng.uniform(0, 2 * np.pi, (2, n))
    wi = np.stack([np.sin(theta[0]) * np.cos(phi[0]), np.sin(theta[0]) * np.sin(phi[0]), np.cos(theta[0])], -1)
    wo = np.stack([np.sin(theta[1]) * np.cos(phi[1]), np.sin(theta[1]) * np.sin(phi[1]), np.cos(theta[1])], -1)
    return np.concatenate([wi, wo, rng.uniform(0.01, 2.0, (n, 3))], axis=1)


def write_csv(path, rows, header=VECTORS):
    lines = [",".join(header)] + [",".join(str(v) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_csv_of_vectors_reads_back(tmp_path):
    rows = samples()
    read = read_samples(write_csv(tmp_path / "m.csv", rows))
    assert read.kind == "csv" and len(read) == len(rows) and read.table is None
    np.testing.assert_allclose(read.wi, rows[:, 0:3], atol=1e-12)
    np.testing.assert_allclose(read.wo, rows[:, 3:6], atol=1e-12)
    np.testing.assert_allclose(read.values, rows[:, 6:9], atol=1e-12)


def test_columns_may_come_in_any_order(tmp_path):
    rows = samples()
    order = [8, 7, 6, 0, 1, 2, 3, 4, 5]
    read = read_samples(write_csv(tmp_path / "m.csv", rows[:, order], [VECTORS[i] for i in order]))
    np.testing.assert_allclose(read.values, rows[:, 6:9], atol=1e-12)


def test_angle_forms_give_the_same_directions(tmp_path):
    rows = samples()
    angles = []
    for start in (0, 3):
        d = rows[:, start:start + 3]
        angles += [np.arccos(d[:, 2]), np.arctan2(d[:, 1], d[:, 0])]
    radians = np.stack(angles + [rows[:, 6], rows[:, 7], rows[:, 8]], axis=1)
    by_radians = read_samples(write_csv(tmp_path / "r.csv", radians, FORMS["radians"]))
    degrees = radians.copy()
    degrees[:, :4] = np.degrees(degrees[:, :4])
    by_degrees = read_samples(write_csv(tmp_path / "d.csv", degrees, FORMS["degrees"]))
    for read in (by_radians, by_degrees):
        np.testing.assert_allclose(read.wi, rows[:, 0:3], atol=1e-9)
        np.testing.assert_allclose(read.wo, rows[:, 3:6], atol=1e-9)


def test_an_npz_of_columns_reads_back(tmp_path):
    rows = samples()
    np.savez(tmp_path / "m.npz", **{name: rows[:, i] for i, name in enumerate(VECTORS)})
    read = read_samples(tmp_path / "m.npz")
    assert read.kind == "npz"
    np.testing.assert_allclose(read.values, rows[:, 6:9])


def test_slightly_long_directions_are_normalised(tmp_path):
    rows = samples()
    rows[:, 0:3] *= 1.0005  # within the 1e-3 tolerance
    read = read_samples(write_csv(tmp_path / "m.csv", rows))
    np.testing.assert_allclose(np.linalg.norm(read.wi, axis=1), 1.0, atol=1e-12)


def _bad(rows, row: int, column: int, value):
    rows = rows.astype(object)
    rows[row - 2, column] = value  # spreadsheet row `row`: the header is row 1
    return rows


@pytest.mark.parametrize("row, column, value, message", [
    (5, 7, "abc", "row 5, column g: 'abc' is not a number"),
    (7, 1, "nan", "row 7: column wi_y is NaN or infinite"),
    (3, 8, "inf", "row 3: column b is NaN or infinite"),
    (9, 6, -0.5, "row 9: negative reflectance"),
    (4, 5, -0.2, "row 4: ω_o"),
    (6, 0, 0.9, "row 6: ω_i has length"),
])
def test_a_bad_value_is_named_by_file_and_row(tmp_path, row, column, value, message):
    path = write_csv(tmp_path / "bad.csv", _bad(samples(), row, column, value))
    with pytest.raises(ValueError) as error:
        read_samples(path)
    assert str(path) in str(error.value) and message in str(error.value)


def test_below_the_horizon_is_named(tmp_path):
    rows = samples()
    rows[10, 0:3] = [0.6, 0.8, 0.0]  # unit length, on the horizon
    with pytest.raises(ValueError, match=r"row 12: ω_i is at or below the horizon"):
        read_samples(write_csv(tmp_path / "m.csv", rows))


def test_the_unit_tolerance_is_stated(tmp_path):
    rows = samples()
    rows[0, 3:6] *= 1.01
    with pytest.raises(ValueError, match=r"row 2: ω_o has length 1\.01.*tolerance 0\.001"):
        read_samples(write_csv(tmp_path / "m.csv", rows))


def test_a_row_with_the_wrong_count_is_named(tmp_path):
    path = write_csv(tmp_path / "m.csv", samples())
    lines = path.read_text().splitlines()
    lines[3] = lines[3].rsplit(",", 1)[0]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=r"m\.csv: row 4: 8 values, the header names 9 columns"):
        read_samples(path)


def test_a_missing_header_is_named(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("\n".join(",".join(map(str, row)) for row in samples()) + "\n")
    with pytest.raises(ValueError, match=r"m\.csv: row 1 must be a header"):
        read_samples(path)


def test_missing_and_unknown_columns_are_named(tmp_path):
    header = list(VECTORS[:-1]) + ["blue"]
    with pytest.raises(ValueError, match=r"row 1 \(header\).*missing \['b'\], unexpected \['blue'\]"):
        read_samples(write_csv(tmp_path / "m.csv", samples(), header))


def test_too_few_samples(tmp_path):
    with pytest.raises(ValueError, match=rf"{MIN_SAMPLES - 1} samples; at least {MIN_SAMPLES}"):
        read_samples(write_csv(tmp_path / "m.csv", samples(MIN_SAMPLES - 1)))


def test_bad_npz_files(tmp_path):
    rows = samples()
    np.savez(tmp_path / "short.npz", **{name: rows[:, i] for i, name in enumerate(VECTORS[:-1])})
    with pytest.raises(ValueError, match=r"short\.npz.*missing \['b'\]"):
        read_samples(tmp_path / "short.npz")
    np.savez(tmp_path / "ragged.npz", **{name: rows[: 60 - (i == 3), i] for i, name in enumerate(VECTORS)})
    with pytest.raises(ValueError, match=r"ragged\.npz: every array must be 1-D"):
        read_samples(tmp_path / "ragged.npz")
    (tmp_path / "broken.npz").write_bytes(b"not a zip")
    with pytest.raises(ValueError, match=r"broken\.npz: not a readable"):
        read_samples(tmp_path / "broken.npz")
    columns = {name: rows[:, i] for i, name in enumerate(VECTORS)}
    columns["r"] = columns["r"].copy()
    columns["r"][41] = -1
    np.savez(tmp_path / "negative.npz", **columns)
    with pytest.raises(ValueError, match=r"negative\.npz: row 42: negative reflectance"):
        read_samples(tmp_path / "negative.npz")


def test_missing_file_and_unknown_format(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.csv"):
        read_samples(tmp_path / "nothing.csv")
    (tmp_path / "m.txt").write_text("x")
    with pytest.raises(ValueError, match=r"m\.txt: read_samples reads .* \.csv .* this file has the suffix '\.txt'"):
        read_samples(tmp_path / "m.txt")


def test_a_merl_file_is_sampled_or_taken_whole(tmp_path):
    table = toy_table(np.random.default_rng(3))
    path = tmp_path / "toy.binary"
    frenbrdf.write_merl(path, table)
    some = read_samples(path, samples=500, seed=4)
    again = read_samples(path, samples=500, seed=4)
    assert some.kind == "merl" and len(some) == 500 and some.table is not None
    np.testing.assert_array_equal(some.values, again.values)
    assert np.all(some.wi[:, 2] > 0) and np.all(some.values >= 0)
    # The sampled values are the table's at those directions (the bins' centres).
    looked_up = frenbrdf.merl_lookup_directions(some.table, some.wi, some.wo, method="nearest")
    np.testing.assert_allclose(looked_up, some.values, rtol=1e-12)
    whole = read_samples(path, samples=None)
    assert len(whole) == int(frenbrdf.valid_mask(table).sum())


def test_a_tables_samples_are_its_values_and_draw_nothing_more():
    from frenbrdf.io.sampling import bin_directions, sample_bins, truth_samples

    table = toy_table(np.random.default_rng(5))
    rng = np.random.default_rng(6)
    bins = sample_bins(table, rng, 400)
    state = rng.bit_generator.state
    values, (wi, wo) = truth_samples(table, bins, rng)
    assert rng.bit_generator.state == state  # results measured on tables before both orders stay reproducible
    np.testing.assert_array_equal(values, table.reshape(3, -1)[:, bins].T)
    expected_wi, expected_wo = bin_directions(bins)
    np.testing.assert_array_equal(wi, expected_wi)
    np.testing.assert_array_equal(wo, expected_wo)


def test_a_measurement_is_sampled_in_both_orders_of_each_pair():
    """A table keeps one order of each pair; a measurement need not be reciprocal, so each bin's pair is evaluated
    in an order drawn at random, and the values are the measurement's at the pair as returned."""
    from frenbrdf.io.sampling import bin_directions, sample_bins, truth_samples

    def lit_from_above(wi, wo):  # not reciprocal: brighter when the light is high
        return np.stack([wi[:, 2], wo[:, 2], np.ones(len(wi))], axis=-1) * 0.3

    bins = sample_bins(toy_table(np.random.default_rng(5)), np.random.default_rng(7), 2000)
    values, (wi, wo) = truth_samples(lit_from_above, bins, np.random.default_rng(8))
    bin_wi, bin_wo = bin_directions(bins)
    as_given = np.all(wi == bin_wi, axis=1) & np.all(wo == bin_wo, axis=1)
    reversed_ = np.all(wi == bin_wo, axis=1) & np.all(wo == bin_wi, axis=1)
    assert np.all(as_given | reversed_)
    assert 0.45 < np.mean(reversed_ & ~as_given) < 0.55  # each order with probability ½
    np.testing.assert_array_equal(values, lit_from_above(wi, wo))
    again = truth_samples(lit_from_above, bins, np.random.default_rng(8))
    np.testing.assert_array_equal(again[0], values)
