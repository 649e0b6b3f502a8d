"""Data: material folders, the split, the log-relative mapping and sampling."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

import frenbrdf
from frenbrdf.data.folders import (
    Split,
    files_mapping,
    list_materials,
    mapped_bank,
    read_tables,
    read_valid_table,
    split_materials,
)
from frenbrdf.io.merl import N_BINS
from frenbrdf.models.mapping import LogRelativeMapping, MappingConfig
from frenbrdf.models.nbrdf import bin_geometry


def test_split_is_70_10_20_disjoint_and_reproducible():
    names = [f"m{i:03d}" for i in range(100)]
    split = split_materials(names, seed=3)
    assert (len(split.train), len(split.val), len(split.test)) == (70, 10, 20)
    assert set(split.train) | set(split.val) | set(split.test) == set(names)
    assert not set(split.train) & set(split.val) and not set(split.train) & set(split.test)
    assert split == split_materials(list(reversed(names)), seed=3)
    assert split != split_materials(names, seed=4)
    assert Split.from_json(split.to_json()) == split


@pytest.mark.parametrize("n", [0, 1, 2])
def test_split_needs_three_materials(n):
    with pytest.raises(ValueError, match="at least 3 materials"):
        split_materials([f"m{i}" for i in range(n)], seed=0)


def test_list_materials_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        list_materials(tmp_path / "absent")
    with pytest.raises(ValueError, match="no material files"):
        list_materials(tmp_path)


def test_a_data_folder_that_cannot_be_listed_says_so_and_not_that_it_is_empty(tmp_path, monkeypatch):
    # Path.glob reads a folder it may not list as an empty one ("holds no material files", which sends a user to
    # synth). Root lists anything, so the refusal is the operating system's, stood in for.
    def refused(path):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr("frenbrdf.data.folders.os.scandir", refused)
    with pytest.raises(PermissionError, match=f"data folder {tmp_path} cannot be listed: Permission denied"):
        list_materials(tmp_path)


@settings(deadline=None)  # the median over two full tables takes ~0.1 s, more on a loaded machine
@given(st.floats(0, 1e4, allow_subnormal=False), st.floats(0, 10), st.sampled_from(["ratio", "one_plus_ratio"]))
def test_mapping_inverts_exactly(f, reference, form):
    mapping = LogRelativeMapping.from_tables(np.full((2, 3, N_BINS), reference),
                                             MappingConfig(reference="per_channel", form=form))
    for value in (f, 0.0):
        mapped = mapping.forward(np.full(3, value), mapping.reference)
        assert np.all(np.isfinite(mapped))
        np.testing.assert_allclose(mapping.inverse(mapped, mapping.reference), value, rtol=1e-12, atol=1e-15)


def test_hyperbrdf_form_is_ln_of_one_plus_the_ratio_and_travels_with_the_model(tmp_path):
    mapping = LogRelativeMapping(np.full(3, 0.1), epsilon=0.002, offset=1.0)
    np.testing.assert_allclose(mapping.forward(np.full(3, 0.3), mapping.reference),
                               np.log(1 + 0.302 / 0.102), rtol=1e-12)
    restored = LogRelativeMapping.from_state(mapping.state())
    assert restored.offset == 1.0 and restored.epsilon == 0.002
    assert LogRelativeMapping.from_state({"reference": np.ones(3), "epsilon": 0.002}).offset == 0.0  # older states
    with pytest.raises(ValueError, match="form"):
        MappingConfig(form="log")


def test_mapping_rejects_bad_reference():
    with pytest.raises(ValueError, match="shape"):
        LogRelativeMapping(np.zeros(4))
    with pytest.raises(ValueError, match="finite and non-negative"):
        LogRelativeMapping(np.array([0.1, np.nan, 0.1]))
    with pytest.raises(ValueError, match="epsilon"):
        MappingConfig(epsilon=0)


def test_reference_is_the_median_over_valid_bins(toy_materials):
    files = list_materials(toy_materials)[:5]
    tables = read_tables(files, progress=False)
    assert np.array_equal(np.isnan(tables[0, 0]), ~frenbrdf.merl_above_horizon().reshape(-1))
    mapping = LogRelativeMapping.from_tables(tables, MappingConfig(reference="per_bin"))
    valid = frenbrdf.merl_above_horizon()
    np.testing.assert_allclose(mapping.reference[:, valid], np.median(tables[:, :, valid.reshape(-1)], axis=0))
    assert np.all(mapping.reference[:, ~valid] == 0)  # missing everywhere: f_ref = 0
    per_channel = LogRelativeMapping.from_tables(tables, MappingConfig(reference="per_channel"))
    assert per_channel.reference.shape == (3,)


def test_the_reference_median_by_chunks_is_the_whole_median():
    """from_tables takes the median a chunk of bins (or a channel) at a time to bound its memory: the same numbers,
    with bins missing in some materials and in all of them, across chunk edges."""
    rng = np.random.default_rng(3)
    tables = rng.lognormal(size=(5, 3, N_BINS))
    tables[:2, :, 1000:300_000] = np.nan  # missing in some materials, across the first chunk's edge
    tables[:, :, -70_000:] = np.nan  # missing in all, across the last edge
    per_bin = LogRelativeMapping.from_tables(tables, MappingConfig(reference="per_bin")).reference.reshape(3, -1)
    np.testing.assert_array_equal(per_bin[:, :1000], np.median(tables[:, :, :1000], axis=0))
    np.testing.assert_array_equal(per_bin[:, 1000:300_000], np.median(tables[2:, :, 1000:300_000], axis=0))
    assert np.all(per_bin[:, -70_000:] == 0)
    per_channel = LogRelativeMapping.from_tables(tables, MappingConfig(reference="per_channel")).reference
    np.testing.assert_array_equal(per_channel, np.nanmedian(tables.transpose(1, 0, 2).reshape(3, -1), axis=1))


@pytest.mark.parametrize("reference", ["per_channel", "per_bin"])
def test_training_reads_its_tables_one_at_a_time_with_the_same_numbers(toy_materials, reference):
    """files_mapping and mapped_bank over tables read one at a time give what all the tables in memory give."""
    files = list_materials(toy_materials)[:4]
    tables = read_tables(files, progress=False)
    config = MappingConfig(reference=reference)
    mapping = files_mapping(files, config, progress=False)
    np.testing.assert_array_equal(mapping.reference, LogRelativeMapping.from_tables(tables, config).reference)
    names = [f.stem for f in files]
    whole, streamed = mapped_bank(names, tables, mapping), mapped_bank(names, map(read_valid_table, files), mapping)
    assert torch.equal(whole.mapped, streamed.mapped) and torch.equal(whole.valid, streamed.valid)
    with pytest.raises(ValueError, match="3 tables for 4 names"):
        mapped_bank(names, map(read_valid_table, files[:3]), mapping)
    with pytest.raises(ValueError, match="more tables than the 3 names"):
        mapped_bank(names[:3], map(read_valid_table, files), mapping)


def test_samples_never_touch_missing_bins(toy_materials):
    files = list_materials(toy_materials)[:3]
    tables = read_tables(files, progress=False)
    bank = mapped_bank([f.stem for f in files], tables, LogRelativeMapping.from_tables(tables, MappingConfig()))
    batch = bank.sample([0, 2], 20_000, torch.Generator().manual_seed(0))
    assert batch.coords.shape == (2, 20_000, 6) and batch.values.shape == (2, 20_000, 3)
    assert torch.isfinite(batch.values).all()
    geometry = bin_geometry()
    valid = torch.from_numpy(frenbrdf.merl_above_horizon().reshape(-1))
    valid_rows = {row.tobytes() for row in geometry.half_diff[valid].numpy()}
    assert all(row.tobytes() in valid_rows for row in batch.coords.reshape(-1, 6)[::10].numpy())
    assert (batch.cos_in > 0).all() and (batch.cos_in <= 1).all()
    assert batch.encoder_input().shape == (2, 20_000, 9)


def test_bin_geometry_matches_the_nbrdf_convention():
    geometry = bin_geometry()
    assert geometry.half_diff.shape == (N_BINS, 6)
    theta_h, theta_d, phi_d = frenbrdf.merl_bin_angles()
    i, j, k = 40, 30, 100
    flat = k + 180 * (j + 90 * i)
    expected = [np.sin(theta_h[i]), 0, np.cos(theta_h[i]),
                np.sin(theta_d[j]) * np.cos(phi_d[k]), np.sin(theta_d[j]) * np.sin(phi_d[k]), np.cos(theta_d[j])]
    np.testing.assert_allclose(geometry.half_diff[flat].numpy(), expected, atol=1e-6)
